#!/usr/bin/env bash
# vm-prepare.sh BUILD_DIR: everything the VM needs, cached under BUILD_DIR/vm-cache (AGVSLAM_VM_CACHE overrides):
#   1. apt-get download: the kernel image linux-image-amd64 depends on, its linux-headers (+ -common, kbuild),
#      v4l2loopback-dkms (source)
#   2. v4l2loopback.ko built against those headers, installed into the extracted module tree, depmod
#   3. a busybox-static initramfs whose /init (tests/vm/init.sh) mounts the host's root over 9p
# Idempotent: each step is skipped when its result exists. Prints the time of each step (VM-TIMING lines).
# Exit 77 (skip) when a tool or the download is unavailable, unless CI=true (then 1).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
. "$here/vm-common.sh"
[ $# -ge 1 ] || { echo "usage: vm-prepare.sh BUILD_DIR" >&2; exit 2; }
vm_paths "$1"
mkdir -p "$VM_CACHE/debs" "$VM_IMAGE_DIR"

for tool in qemu-system-x86_64 apt-get dpkg-deb make gcc depmod cpio gzip; do
  command -v "$tool" >/dev/null || vm_skip "$tool not found (bash deploy/install-deps.sh installs the VM tools)"
done
busybox=""
for b in /bin/busybox /usr/bin/busybox; do
  if [ -x "$b" ] && file -L "$b" 2>/dev/null | grep -q "statically linked"; then busybox=$b; fi
done
if [ -z "$busybox" ] && [ -x /bin/busybox ] && ! ldd /bin/busybox >/dev/null 2>&1; then busybox=/bin/busybox; fi
[ -n "$busybox" ] || vm_skip "no static busybox (package busybox-static)"

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN{printf "%.1f", b-a}'; }

# 1. Downloads.
t=$(now)
if [ ! -f "$VM_CACHE/kver" ]; then
  image_pkg=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/{print $2; exit}')
  if [ -z "$image_pkg" ] && [ "$(id -u)" -eq 0 ]; then  # no package lists yet on this machine
    apt-get update -qq >"$VM_CACHE/apt-update.log" 2>&1 || true
    image_pkg=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/{print $2; exit}')
  fi
  [ -n "$image_pkg" ] || vm_skip "apt-cache does not know linux-image-amd64 (run apt-get update)"
  kver=${image_pkg#linux-image-}
  series=$(echo "$kver" | cut -d. -f1,2)
  abi=${kver%-amd64}
  pkgs=("$image_pkg" "linux-headers-$kver" "linux-headers-$abi-common" "linux-kbuild-$series" v4l2loopback-dkms)
  vm_log "downloading ${pkgs[*]}"
  (cd "$VM_CACHE/debs" && apt-get download "${pkgs[@]}" >"$VM_CACHE/download.log" 2>&1) ||
    vm_skip "apt-get download failed (no network or package lists?): $(tail -2 "$VM_CACHE/download.log")"
  rm -rf "$VM_ROOT"
  mkdir -p "$VM_ROOT"
  for d in "$VM_CACHE"/debs/*.deb; do dpkg-deb -x "$d" "$VM_ROOT"; done
  # The headers' Makefile includes the -common tree by absolute path: point it into the extracted tree.
  sed -i "s|^include /usr/src/|include $VM_ROOT/usr/src/|" "$VM_ROOT/usr/src/linux-headers-$kver/Makefile"
  echo "$kver" >"$VM_CACHE/kver"
  echo "VM-TIMING download+extract $(elapsed "$t") s ($(du -sh "$VM_CACHE/debs" | cut -f1) of packages)"
fi
kver=$(cat "$VM_CACHE/kver")
moddir=$VM_ROOT/lib/modules/$kver

# 2. v4l2loopback against the downloaded headers.
t=$(now)
if [ ! -f "$moddir/updates/v4l2loopback.ko" ]; then
  src=$(ls -d "$VM_ROOT"/usr/src/v4l2loopback-* | head -1)
  rm -rf "$VM_CACHE/v4l2loopback-build"
  cp -r "$src" "$VM_CACHE/v4l2loopback-build"
  make -C "$VM_ROOT/usr/src/linux-headers-$kver" M="$VM_CACHE/v4l2loopback-build" modules \
    >"$VM_CACHE/module-build.log" 2>&1 || { tail -20 "$VM_CACHE/module-build.log" >&2; echo "vm: v4l2loopback build failed" >&2; exit 1; }
  mkdir -p "$moddir/updates"
  cp "$VM_CACHE/v4l2loopback-build/v4l2loopback.ko" "$moddir/updates/"
  depmod -b "$VM_ROOT" "$kver"
  echo "VM-TIMING v4l2loopback build $(elapsed "$t") s"
fi

# 3. initramfs: busybox, /init, the modules needed to mount 9p (in load order).
t=$(now)
initrd=$VM_IMAGE_DIR/initramfs.cpio.gz
if [ ! -f "$initrd" ] || [ "$here/init.sh" -nt "$initrd" ]; then
  stage=$VM_CACHE/initramfs
  rm -rf "$stage"
  mkdir -p "$stage"/{bin,proc,sys,dev,newroot,modules}
  cp "$busybox" "$stage/bin/busybox"
  cp "$here/init.sh" "$stage/init"
  chmod +x "$stage/init"
  : >"$stage/modules.order"
  for m in virtio_pci 9pnet_virtio 9p; do modprobe -d "$VM_ROOT" -S "$kver" --show-depends "$m"; done | awk '$1=="insmod"{print $2}' |
    while read -r ko; do
      name=$(basename "$ko")
      grep -qx "$name" "$stage/modules.order" && continue
      cp "$ko" "$stage/modules/$name"
      echo "$name" >>"$stage/modules.order"
    done
  [ -s "$stage/modules.order" ] || { echo "vm: could not resolve the 9p modules in $moddir" >&2; exit 1; }
  (cd "$stage" && find . | cpio -o -H newc --quiet | gzip -1 >"$initrd")
  cp "$VM_ROOT/boot/vmlinuz-$kver" "$VM_IMAGE_DIR/vmlinuz"
  echo "VM-TIMING initramfs $(elapsed "$t") s (modules: $(tr '\n' ' ' <"$stage/modules.order"))"
fi
echo "vm: ready: kernel $kver, $VM_IMAGE_DIR/{vmlinuz,initramfs.cpio.gz}, modules $moddir"
