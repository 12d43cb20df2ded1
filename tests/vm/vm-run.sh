#!/usr/bin/env bash
# vm-run.sh [--build DIR] [--timeout S] [--smp N] [--mem MB] [--log FILE] -- COMMAND [ARG...]
#
# Boots Debian's kernel under qemu-system-x86_64 (TCG, no KVM, serial console) and runs COMMAND as root inside
# it, with the host's root file system (read-only) as the VM's root, so every host binary and library is there;
# the build folder is mounted read-write at its own path (COMMAND starts there). Prints the VM's console and
# exits with COMMAND's exit status; 124 when the VM does not finish within --timeout (it is killed); 77 (skip)
# when the VM is not prepared (run vm-prepare.sh) or qemu is missing, unless CI=true.
#
# Inside the VM: `modprobe` works for every module of the Debian kernel plus v4l2loopback (a wrapper on PATH
# points it at the downloaded module tree); the environment has AGVSLAM_BUILD (the build folder), AGVSLAM_SOURCE
# (the source tree), AGVSLAM_SHARED_DIR, CI, and VM_LOG_DIR (a folder in the build tree for logs that should
# come back to the host).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
. "$here/vm-common.sh"
source_dir=$(cd "$here/../.." && pwd)
build=${AGVSLAM_BUILD:-}
timeout=300 smp=${AGVSLAM_VM_SMP:-2} mem=${AGVSLAM_VM_MEM_MB:-1536} log=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --timeout) timeout=$2; shift 2 ;;
    --smp) smp=$2; shift 2 ;;
    --mem) mem=$2; shift 2 ;;
    --log) log=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "vm-run.sh: unknown option $1 (expected --build, --timeout, --smp, --mem, --log, then -- COMMAND)" >&2; exit 2 ;;
  esac
done
[ $# -ge 1 ] || { echo "vm-run.sh: expected -- COMMAND [ARG...]" >&2; exit 2; }
[ -n "$build" ] || { echo "vm-run.sh: expected --build DIR (or AGVSLAM_BUILD)" >&2; exit 2; }
vm_paths "$build"
command -v qemu-system-x86_64 >/dev/null || vm_skip "qemu-system-x86_64 not found (package qemu-system-x86)"
[ -f "$VM_IMAGE_DIR/vmlinuz" ] && [ -f "$VM_IMAGE_DIR/initramfs.cpio.gz" ] && [ -f "$VM_CACHE/kver" ] ||
  vm_skip "VM not prepared under $VM_CACHE (tests/vm/vm-prepare.sh $VM_BUILD; needs the Debian package downloads)"
kver=$(cat "$VM_CACHE/kver")

# The script the VM runs: environment, a modprobe wrapper, then COMMAND.
run_dir=$(mktemp -d "$VM_BUILD/vm-runs/run.XXXXXX" 2>/dev/null || { mkdir -p "$VM_BUILD/vm-runs"; mktemp -d "$VM_BUILD/vm-runs/run.XXXXXX"; })
[ -n "$log" ] || log=$run_dir/console.log
shared=${AGVSLAM_SHARED_DIR:-$source_dir/../shared}
# Host folders the VM must see where it mounts empty tmpfs (/tmp, /run, /var/tmp): a checkout made with mktemp -d.
keep=$source_dir
# ../shared may be a link (to a folder outside the checkout's tmpfs): the VM gets the folder it points to.
if [ -d "$shared" ]; then
  shared=$(cd "$shared" && pwd -P)
  keep="$keep,$shared"
fi
{
  echo '#!/bin/bash'
  echo "export PATH=/tmp/vm-bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/tmp LANG=C.UTF-8"
  printf 'export AGVSLAM_BUILD=%q AGVSLAM_SOURCE=%q AGVSLAM_SHARED_DIR=%q CI=%q VM_LOG_DIR=%q\n' \
    "$VM_BUILD" "$source_dir" "$shared" "${CI:-}" "$run_dir"
  echo 'mkdir -p /tmp/vm-bin'
  printf 'printf "#!/bin/sh\\nexec /sbin/modprobe -d /tmp/vm-modroot \\"\\$@\\"\\n" > /tmp/vm-bin/modprobe\n'
  echo 'chmod +x /tmp/vm-bin/modprobe'
  printf 'cd %q\n' "$VM_BUILD"
  printf '%q ' "$@"
  echo
} >"$run_dir/run.sh"

accel_note="tcg"
t0=$(date +%s.%N)
set +e
timeout -k 10 "$timeout" qemu-system-x86_64 -machine q35 -accel tcg -cpu max -smp "$smp" -m "$mem" \
  -nographic -no-reboot -monitor none -nic none \
  -kernel "$VM_IMAGE_DIR/vmlinuz" -initrd "$VM_IMAGE_DIR/initramfs.cpio.gz" \
  -append "console=ttyS0 quiet loglevel=4 panic=-1 agvslam.run=$run_dir/run.sh agvslam.build=$VM_BUILD agvslam.keep=$keep" \
  -fsdev local,id=hostroot,path=/,security_model=none,readonly=on,multidevs=remap \
  -device virtio-9p-pci,fsdev=hostroot,mount_tag=hostroot \
  -fsdev local,id=build,path="$VM_BUILD",security_model=none,multidevs=remap \
  -device virtio-9p-pci,fsdev=build,mount_tag=build \
  -fsdev local,id=modules,path="$VM_ROOT/lib/modules",security_model=none,readonly=on \
  -device virtio-9p-pci,fsdev=modules,mount_tag=modules \
  </dev/null >"$log" 2>&1
qemu_rc=$?
set -e
t1=$(date +%s.%N)
tr -d '\r' <"$log" | sed -n '/AGVSLAM-VM-READY/,$p' | sed 's/^.*AGVSLAM-VM-READY/AGVSLAM-VM-READY/'
ready=$(tr -d '\r' <"$log" | grep -ao 'AGVSLAM-VM-READY [0-9.]*' | head -1 | cut -d' ' -f2)
status=$(tr -d '\r' <"$log" | grep -ao 'AGVSLAM-VM-EXIT [0-9]*' | head -1 | cut -d' ' -f2)
total=$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')
echo "VM-TIMING kernel $kver ($accel_note, smp $smp): boot to script ${ready:-?} s (guest uptime), whole run $total s; console log $log"
if [ -z "$status" ]; then
  echo "--- no AGVSLAM-VM-EXIT marker; last console lines:"
  tr -d '\r' <"$log" | tail -30
  if [ "$qemu_rc" -eq 124 ] || [ "$qemu_rc" -eq 137 ]; then echo "vm-run.sh: timed out after $timeout s" >&2; exit 124; fi
  exit 1
fi
exit "$status"
