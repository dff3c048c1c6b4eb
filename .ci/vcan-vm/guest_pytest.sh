#!/bin/sh
# Runs inside the guest (as root, in the repo): brings up vcan0 and runs the SocketCAN tests.
# Usage: guest_pytest.sh PYTHON OUTDIR [extra pytest args...]
#   PYTHON  the project venv's python (the host path: the guest sees the host's files)
#   OUTDIR  a host dir made writable in the guest (VCAN_VM_RWDIR): junit.xml and pytest.rc
#           are written there, so the host can tell "tests failed" from "guest never finished"
# The repo is read-only in the guest unless it is in VCAN_VM_RWDIR too; /tmp is a tmpfs
# overlay, so pytest's tmp_path lives there (--basetemp).
set -u
PY=$1
OUT=$2
shift 2
fail() { echo "guest: $*" >&2; echo 90 > "$OUT/pytest.rc"; exit 90; }

echo "guest: kernel $(uname -r), $(nproc) CPU(s), $(awk '/MemTotal/ {print int($2/1024)}' /proc/meminfo) MiB"
modprobe vcan || fail "modprobe vcan failed"
modprobe can-raw || fail "modprobe can-raw failed"
ip link add dev vcan0 type vcan || fail "ip link add vcan0 failed"
ip link set up vcan0 || fail "ip link set up vcan0 failed"
ip -brief link show vcan0
[ -e /sys/class/net/vcan0 ] || fail "/sys/class/net/vcan0 missing after set-up"
command -v candump >/dev/null || fail "candump (can-utils) not found"

export PYTHONDONTWRITEBYTECODE=1 PYTHONUNBUFFERED=1 HOME=/tmp CI=true
# one realtime run took 344 s alone and over 600 s in the full selection under TCG
export THIL_TEST_RUN_TIMEOUT_S=1500
"$PY" -m pytest -m socketcan -p no:cacheprovider --basetemp=/tmp/thil-pytest \
  --junitxml="$OUT/junit.xml" "$@"
rc=$?
echo "$rc" > "$OUT/pytest.rc"
sync
exit "$rc"
