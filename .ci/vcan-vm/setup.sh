#!/bin/bash
# Host set-up for the SocketCAN guest (Debian 12, run as root). Idempotent: when everything
# is already there it does no apt or pip work and takes about a second.
#   - QEMU, Debian's kernel (its modules carry vcan and can-raw; the guest loads them from the
#     host's /lib/modules), can-utils, busybox (virtme-ng's initramfs), iproute2/kmod (used
#     in the guest, which runs on the host's root filesystem);
#   - virtme-ng in a venv under $VCAN_VM_HOME (default /tmp/vcan-vm).
# From scratch: ~75 s, ~100 MB download, ~550 MB disk; it may upgrade systemd packages.
# Env: VCAN_VM_HOME, VCAN_VM_VNG_VERSION (default 1.42, the verified virtme-ng).
set -euo pipefail
D=${VCAN_VM_HOME:-/tmp/vcan-vm}
VNG_VERSION=${VCAN_VM_VNG_VERSION:-1.42}
PKGS=(qemu-system-x86 linux-image-amd64 can-utils busybox-static iproute2 kmod python3-venv)

retry() {  # retry CMD...: three attempts, for network hiccups
  local n
  for n in 1 2 3; do
    "$@" && return 0
    echo "setup: attempt $n failed: $*" >&2
    [ "$n" = 3 ] || sleep $((n * 5))
  done
  return 1
}

missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  [ "$(id -u)" = 0 ] || { echo "setup: need root to install: ${missing[*]}" >&2; exit 1; }
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  retry apt-get -q update
  retry apt-get -q install -y --no-install-recommends \
    -o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold "${missing[@]}"
else
  echo "setup: apt packages already installed"
fi

KVER=$(ls /lib/modules | grep -E -- '-amd64$' | sort -V | tail -1 || true)
if [ -z "$KVER" ] || [ -z "$(find "/lib/modules/$KVER" -name 'vcan.ko*' -print -quit)" ]; then
  echo "setup: no Debian kernel with vcan under /lib/modules (linux-image-amd64)" >&2
  exit 1
fi

have=$("$D/venv/bin/python" -c 'import importlib.metadata as m; print(m.version("virtme-ng"))' \
       2>/dev/null || true)
if [ "$have" = "$VNG_VERSION" ] && [ -x "$D/venv/bin/vng" ]; then
  echo "setup: virtme-ng $have already in $D/venv"
else
  echo "setup: installing virtme-ng==$VNG_VERSION into $D/venv"
  mkdir -p "$D"
  rm -rf "$D/venv"
  /usr/bin/python3 -m venv "$D/venv"
  retry "$D/venv/bin/python" -m pip install -q --disable-pip-version-check \
    "virtme-ng==$VNG_VERSION"
fi
echo "setup: ready (kernel $KVER, $("$D/venv/bin/vng" --version 2>&1 | head -1))"
