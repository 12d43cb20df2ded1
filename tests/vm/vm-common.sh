# Shared by the VM harness scripts (sourced). Skips (exit 77) where the VM cannot be had, except under CI=true,
# where that is a failure.
AGVSLAM_VM_SKIP=77

vm_log() { echo "[vm $(date +%H:%M:%S)] $*" >&2; }

vm_skip() {
  if [ "${CI:-}" = "true" ] || [ "${CI:-}" = "1" ]; then
    echo "vm: FAIL (CI=true, so not skipped): $*" >&2
    exit 1
  fi
  echo "vm: SKIP: $*" >&2
  exit "$AGVSLAM_VM_SKIP"
}

# vm_paths BUILD_DIR: sets VM_BUILD, VM_CACHE (downloads, extracted kernel, module, initramfs; never committed).
vm_paths() {
  VM_BUILD=$(cd "$1" && pwd)
  VM_CACHE=${AGVSLAM_VM_CACHE:-$VM_BUILD/vm-cache}
  VM_ROOT=$VM_CACHE/root
  VM_IMAGE_DIR=$VM_CACHE/image
}
