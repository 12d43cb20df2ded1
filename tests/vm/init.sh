#!/bin/busybox sh
# /init of the VM's initramfs (built by vm-prepare.sh). Mounts the host's root file system read-only over 9p
# (tag hostroot) so the project's binaries run with the host's libraries, the build folder read-write at its own
# path (tag build), the kernel modules (tag modules), tmpfs for /tmp, /run, /var/tmp; then runs the script
# named on the kernel command line (agvslam.run=PATH) in that root and powers off. The serial console carries
# AGVSLAM-VM-READY <uptime s> before the script and AGVSLAM-VM-EXIT <status> after it.
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in $(cat /modules.order); do insmod /modules/$m || echo "init: insmod $m failed"; done

run=""; build=""
for arg in $(cat /proc/cmdline); do
  case "$arg" in
    agvslam.run=*) run=${arg#agvslam.run=} ;;
    agvslam.build=*) build=${arg#agvslam.build=} ;;
  esac
done

opts=trans=virtio,version=9p2000.L,msize=512000
fail() { echo "init: $*"; echo "AGVSLAM-VM-EXIT 125"; poweroff -f; }
mount -t 9p -o $opts,ro,cache=loose hostroot /newroot || fail "cannot mount the host root over 9p"
mount -t 9p -o $opts,cache=none build /newroot$build || fail "cannot mount the build folder $build"
for d in tmp run var/tmp; do mount -t tmpfs -o mode=1777 tmpfs /newroot/$d; done
mount -t proc proc /newroot/proc
mount -t sysfs sys /newroot/sys
mount -t devtmpfs dev /newroot/dev
mkdir -p /newroot/dev/pts /newroot/dev/shm
mount -t devpts devpts /newroot/dev/pts
mount -t tmpfs -o mode=1777 tmpfs /newroot/dev/shm
# modprobe inside the root finds the modules under $AGVSLAM_VM_MODROOT/lib/modules (the host has none of its own).
mkdir -p /newroot/tmp/vm-modroot/lib/modules
mount -t 9p -o $opts,ro modules /newroot/tmp/vm-modroot/lib/modules || fail "cannot mount the modules"
ip link set lo up 2>/dev/null

echo "AGVSLAM-VM-READY $(cut -d' ' -f1 /proc/uptime)"
chroot /newroot /bin/bash "$run"
rc=$?
echo "AGVSLAM-VM-EXIT $rc"
sync
poweroff -f
