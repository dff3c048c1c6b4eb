#!/bin/sh
# Self-check of the recipe, independent of the project's tests. Runs inside the guest:
#   .ci/vcan-vm/run_in_vm.sh sh .ci/vcan-vm/guest_test.sh /tmp/thil-ci-venv/bin/python
# vcan0 up, candump sees three frames from cansend, python-can round trips (can_rtt.py).
# PYTHON (first argument) must have python-can; without it the python-can part is skipped.
set -e
PY=${1:-}
modprobe vcan
modprobe can-raw
ip link add dev vcan0 type vcan
ip link set up vcan0
ip -details link show vcan0
lsmod | grep -E '^(vcan|can_raw|can) '
candump -L -n 3 vcan0 > /tmp/candump.txt &
CD=$!
# candump has no readiness signal: give it a moment (this is a diagnostic, not a test)
sleep 0.5
cansend vcan0 123#DEADBEEF
cansend vcan0 1F334455#1122334455667788
cansend vcan0 7FF#R
wait $CD
echo "candump got:"; cat /tmp/candump.txt
test "$(wc -l < /tmp/candump.txt)" -eq 3
if [ -n "$PY" ]; then
  "$PY" "$(dirname "$0")/can_rtt.py" 200
else
  echo "guest_test: no PYTHON given, python-can round trips skipped"
fi
