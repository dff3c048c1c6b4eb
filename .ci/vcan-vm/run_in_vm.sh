#!/bin/bash
# Usage: run_in_vm.sh 'shell command'   (or: run_in_vm.sh cmd arg1 arg2 ...)
# Boots Debian's linux-image-amd64 kernel in a QEMU guest (virtme-ng) that sees the host
# root read-only (9p, with tmpfs overlays on /etc /usr /var /tmp /home ...; /root and other
# paths are plain read-only), runs the command as root in the current directory, powers
# off, and exits with the command's status: 124 on timeout, 255 if the guest died,
# 125 if the VM could not be prepared. The guest does not inherit this environment.
# Env: VCAN_VM_HOME (default /tmp/vcan-vm: where setup.sh put the venv),
#      VCAN_VM_ACCEL=tcg|kvm (default: kvm only if /proc/cpuinfo shows vmx/svm),
#      VCAN_VM_RWDIR=/host/dir[:/other/dir] (made writable in the guest),
#      VCAN_VM_TIMEOUT=seconds (default 900), VCAN_VM_MEM (default 1G), VCAN_VM_CPUS (default 2).
set -u
D=${VCAN_VM_HOME:-/tmp/vcan-vm}
export PATH=$D/venv/bin:$PATH
command -v vng >/dev/null || { echo "run_in_vm: no vng in $D/venv (run setup.sh)" >&2; exit 125; }
KVER=$(ls /lib/modules | grep -E -- '-amd64$' | sort -V | tail -1)
[ -n "$KVER" ] || { echo "run_in_vm: no Debian kernel in /lib/modules (apt-get install linux-image-amd64)" >&2; exit 125; }
# PVH-boot the uncompressed vmlinux: skips ~3 s of xz decompression under TCG.
KERNEL=$D/vmlinux-$KVER
if [ ! -s "$KERNEL" ]; then
  python3 - "/boot/vmlinuz-$KVER" "$KERNEL.tmp.$$" <<'PY' || exit 125
import lzma, sys
d = open(sys.argv[1], 'rb').read()
i = d.find(b'\xfd7zXZ\x00')
open(sys.argv[2], 'wb').write(lzma.LZMADecompressor().decompress(d[i:]))
PY
  mv "$KERNEL.tmp.$$" "$KERNEL"
fi
ACCEL=${VCAN_VM_ACCEL:-}
if [ -z "$ACCEL" ]; then
  if [ -w /dev/kvm ] && grep -qwE 'vmx|svm' /proc/cpuinfo; then ACCEL=kvm; else ACCEL=tcg; fi
fi
OPTS=(--force-9p --memory "${VCAN_VM_MEM:-1G}" --cpus "${VCAN_VM_CPUS:-2}")
[ "$ACCEL" = tcg ] && OPTS+=(--disable-kvm)
if [ -n "${VCAN_VM_RWDIR:-}" ]; then
  IFS=: read -r -a RWDIRS <<< "$VCAN_VM_RWDIR"
  for d in "${RWDIRS[@]}"; do [ -n "$d" ] && OPTS+=(--rwdir="$d"); done
fi
# Keep udev coldplug from loading slow, useless drivers (kvm alone costs ~4 s under TCG).
BL=kvm_amd,kvm_intel,kvm,ahci,libahci,sr_mod,cdrom,iTCO_wdt,iTCO_vendor_support,i2c_i801,lpc_ich,pcspkr
BL=$BL,aesni_intel,ghash_clmulni_intel,powernow_k8,i6300esb,psmouse,sg,evdev,button,joydev,serio_raw
BL=$BL,crc32_pclmul,polyval_clmulni,sha512_ssse3,sha256_ssse3,sha1_ssse3
if [ $# -eq 1 ]; then CMD=$1; else CMD=$(printf '%q ' "$@"); fi
CMD="export VCAN_VM_HOME=$(printf %q "$D"); $CMD"
# `timeout` without --foreground runs vng in its own process group and, on timeout, kills the
# whole group: vng runs QEMU through a shell, and --foreground would leave QEMU running.
# A signal to this script is passed on to that group for the same reason.
# QEMU re-opens /proc/self/fd/1 and /proc/self/fd/2 with O_TRUNC: if they are regular files
# (e.g. `run_in_vm.sh cmd >> ci.log`) earlier contents get wiped. Always hand it pipes.
timeout -k 10 "${VCAN_VM_TIMEOUT:-900}" \
  vng "${OPTS[@]}" -a "modprobe.blacklist=$BL" --run "$KERNEL" --exec "$CMD" \
  </dev/null > >(cat) 2> >(cat >&2) &
pid=$!
trap 'kill -TERM -- "-$pid" 2>/dev/null; trap - INT TERM HUP' INT TERM HUP
while :; do
  wait "$pid"; rc=$?
  kill -0 "$pid" 2>/dev/null || break   # else: wait was interrupted by a signal
done
sleep 0.2   # let the output relays flush
case $rc in
  124) echo "run_in_vm: guest timed out after ${VCAN_VM_TIMEOUT:-900} s" >&2 ;;
  255) echo "run_in_vm: guest died (QEMU/vng exit 255)" >&2 ;;
esac
exit "$rc"
