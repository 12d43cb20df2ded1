#!/usr/bin/env bash
# Installs every build, test and run-time dependency of agvslam from Debian packages.
# Idempotent: safe to run again; does nothing but a package-list refresh when all is installed.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libopencv-dev libeigen3-dev libceres-dev
  libdeflate-dev  # simulator PNG writer (deflate of the image data)
  zlib1g-dev  # CRC-32 of saved maps
  libyaml-cpp-dev libspdlog-dev libfmt-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  cyclonedds-dev cyclonedds-tools can-utils iproute2 util-linux  # pose outputs: DDS (idlc), CAN tools, netns tests
  libsqlite3-dev  # rosbag2 recordings (.db3) as a dataset
  libssl-dev openssl  # DDS Security: the keystore checks (libcrypto), deploy/make-keystore.sh
  libv4l-dev v4l-utils qemu-system-x86 busybox-static kmod cpio  # V4L2 camera (libv4l2); VM harness (tests/vm)
  clang-format  # the layout in .clang-format, checked by the format test
  clang llvm libclang-rt-14-dev  # tests/fuzz: clang++, libFuzzer (only recommended by clang-14: --no-install-recommends
  # would leave it out), llvm-symbolizer for the sanitizers' stack traces
  libsystemd-dev systemd  # agvslamd: sd_notify (READY/WATCHDOG/STATUS/STOPPING); systemd-analyze verify in the tests
  python3-torch python3-onnx python3-opencv python3-numpy  # src/semantic/training: train and export the segmenter
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
