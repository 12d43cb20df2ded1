#!/bin/busybox sh
# /init of the VM's initramfs (built by vm-prepare.sh). Mounts the host's root file system read-only over 9p
# (tag hostroot) so the project's binaries run with the host's libraries, the build folder read-write at its own
# path (tag build), the kernel modules (tag modules), tmpfs for /tmp, /run, /var/tmp (with the host folders named
# by agvslam.keep=A,B shown through them: a checkout under /tmp); then runs the script
# named on the kernel command line (agvslam.run=PATH) in that root and powers off. The serial console carries
# AGVSLAM-VM-READY <uptime s> before the script and AGVSLAM-VM-EXIT <status> after it.
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in $(cat /modules.order); do insmod /modules/$m || echo "init: insmod $m failed"; done

run=""; build=""; keep=""
for arg in $(cat /proc/cmdline); do
  case "$arg" in
    agvslam.run=*) run=${arg#agvslam.run=} ;;
    agvslam.build=*) build=${arg#agvslam.build=} ;;
    agvslam.keep=*) keep=${arg#agvslam.keep=} ;;
  esac
done

opts=trans=virtio,version=9p2000.L,msize=512000
fail() { echo "init: $*"; echo "AGVSLAM-VM-EXIT 125"; poweroff -f; }
mount -t 9p -o $opts,ro,cache=loose hostroot /newroot || fail "cannot mount the host root over 9p"
# A second view of the host root, so that folders under /tmp, /run, /var/tmp stay reachable once tmpfs covers them.
mkdir -p /hostview && mount -o bind /newroot /hostview || fail "cannot bind the host root"
for d in tmp run var/tmp; do mount -t tmpfs -o mode=1777 tmpfs /newroot/$d; done
for p in $(echo "$keep" | tr ',' ' '); do
  case "$p/" in
    /tmp/*|/run/*|/var/tmp/*)
      [ -d "/hostview$p" ] || continue
      mkdir -p "/newroot$p" && mount -o bind "/hostview$p" "/newroot$p" || fail "cannot show the host folder $p" ;;
  esac
done
mkdir -p "/newroot$build" 2>/dev/null
mount -t 9p -o $opts,cache=none build /newroot$build || fail "cannot mount the build folder $build"
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
