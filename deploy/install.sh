#!/usr/bin/env bash
# Installs agvslamd on a vehicle computer (run as root after building):
#   bash deploy/install-deps.sh && cmake --preset release && cmake --build --preset release
#   sudo deploy/install.sh [--build build/release] [--prefix /usr/local] [--udev] [--enable]
#   sudo deploy/install.sh --destdir /tmp/stage ...      stage the files only (no user, no systemctl; packaging)
#
# What goes where:
#   PREFIX/bin/                     agvslamd and the field tools (agvslam-echo, -camera, -can-decode,
#                                   -pose-replay, -run, -eval) that were built
#   /etc/agvslam/                   agvslamd.yaml (from params/agvslamd.yaml) with the stage files it names
#                                   (features, slam, dynamic, stereo, place + a link to the shipped vocabulary,
#                                   camera_v4l2, the example calibration) and
#                                   cyclonedds-loopback.xml; files that exist are kept, the new version is put
#                                   beside them as *.new
#   PREFIX/share/agvslam/           agvslam.dbc (the CAN frames), params/ (all shipped params), the udev rule
#                                   example, README.md, make-keystore.sh (the keystore of the config's
#                                   dds_security section)
#   /etc/systemd/system/agvslamd.service   deploy/agvslamd.service with PREFIX in ExecStart
#   /etc/udev/rules.d/99-agvslam-camera.rules   only with --udev (edit the serial numbers first)
#   system user and group `agvslam`, member of `video` (the service runs as it)
# --enable: systemctl enable --now agvslamd afterwards. The service's StateDirectory (/var/lib/agvslam) and
# LogsDirectory (/var/log/agvslam) are created by systemd.
set -euo pipefail

src=$(cd "$(dirname "$0")/.." && pwd)
build=$src/build/release
prefix=/usr/local
destdir=""
udev=0
enable=0
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$(cd "$2" && pwd); shift 2 ;;
    --prefix) prefix=$2; shift 2 ;;
    --destdir) destdir=$2; shift 2 ;;
    --udev) udev=1; shift ;;
    --enable) enable=1; shift ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    *) echo "install.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
[ -x "$build/bin/agvslamd" ] || { echo "install.sh: $build/bin/agvslamd not built (cmake --build --preset release)" >&2; exit 2; }
if [ -z "$destdir" ] && [ "$(id -u)" -ne 0 ]; then
  echo "install.sh: run as root (or stage with --destdir DIR)" >&2
  exit 2
fi

d=$destdir
bindir=$d$prefix/bin
share=$d$prefix/share/agvslam
etc=$d/etc/agvslam
install -d -m 0755 "$bindir" "$share" "$share/params" "$d/etc/systemd/system"
install -d -m 0755 "$etc"

echo "install.sh: binaries -> $bindir"
for tool in agvslamd agvslam-echo agvslam-camera agvslam-can-decode agvslam-pose-replay agvslam-run agvslam-eval; do
  if [ -x "$build/bin/$tool" ]; then
    install -m 0755 "$build/bin/$tool" "$bindir/$tool"
    echo "  $tool"
  fi
done

# A configuration file is never overwritten: the shipped version lands beside it as .new.
install_config() {  # SRC DEST
  if [ -e "$2" ] && ! cmp -s "$1" "$2"; then
    install -m 0644 "$1" "$2.new"
    echo "  $2 kept (new version: $2.new)"
  else
    install -m 0644 "$1" "$2"
    echo "  $2"
  fi
}
echo "install.sh: configuration -> $etc"
# The shipped agvslamd.yaml names the CAN DBC relative to the source tree; installed, it lies in the shared files.
daemon_yaml=$(mktemp)
trap 'rm -f "$daemon_yaml"' EXIT
sed "s|dbc: \.\./deploy/agvslam\.dbc|dbc: $prefix/share/agvslam/agvslam.dbc|" "$src/params/agvslamd.yaml" > "$daemon_yaml"
install_config "$daemon_yaml" "$etc/agvslamd.yaml"
for f in features.yaml slam.yaml dynamic.yaml stereo.yaml camera_v4l2.yaml agvslamd_calibration_example.yaml; do
  install_config "$src/params/$f" "$etc/$f"
done
install_config "$src/deploy/cyclonedds-loopback.xml" "$etc/cyclonedds-loopback.xml"
install_config "$src/params/place.yaml" "$etc/place.yaml"
# place.yaml names vocabulary/<file> relative to its folder: the shipped vocabulary stays in the shared files.
ln -sfn "../..$prefix/share/agvslam/params/vocabulary" "$etc/vocabulary"

echo "install.sh: shared files -> $share"
install -m 0644 "$src/deploy/agvslam.dbc" "$share/agvslam.dbc"
install -m 0755 "$src/deploy/make-keystore.sh" "$share/make-keystore.sh"
install -m 0644 "$src/deploy/99-agvslam-camera.rules" "$share/99-agvslam-camera.rules"
install -m 0644 "$src/README.md" "$share/README.md"
cp -r "$src/params/." "$share/params/"

echo "install.sh: systemd unit -> $d/etc/systemd/system/agvslamd.service"
sed "s|/usr/local/bin/agvslamd|$prefix/bin/agvslamd|g; s|file:///usr/local/share/agvslam|file://$prefix/share/agvslam|g" \
  "$src/deploy/agvslamd.service" > "$d/etc/systemd/system/agvslamd.service"
chmod 0644 "$d/etc/systemd/system/agvslamd.service"

if [ "$udev" = 1 ]; then
  install -d -m 0755 "$d/etc/udev/rules.d"
  install -m 0644 "$src/deploy/99-agvslam-camera.rules" "$d/etc/udev/rules.d/99-agvslam-camera.rules"
  echo "install.sh: udev rule -> $d/etc/udev/rules.d/99-agvslam-camera.rules (edit the serial numbers)"
fi

if [ -n "$destdir" ]; then
  echo "install.sh: staged under $destdir (no user created, systemd not told)"
  exit 0
fi

if ! getent group agvslam >/dev/null; then groupadd --system agvslam; fi
if ! id agvslam >/dev/null 2>&1; then
  useradd --system --gid agvslam --home-dir /var/lib/agvslam --no-create-home --shell /usr/sbin/nologin \
    --comment "agvslam daemon" agvslam
  echo "install.sh: created system user agvslam"
fi
getent group video >/dev/null || groupadd --system video
usermod -a -G video agvslam
chgrp agvslam "$etc"/*.yaml "$etc"/*.xml 2>/dev/null || true

if [ "$udev" = 1 ] && command -v udevadm >/dev/null; then
  udevadm control --reload || true
  udevadm trigger --subsystem-match=video4linux || true
fi
if command -v systemctl >/dev/null && [ -d /run/systemd/system ]; then
  systemctl daemon-reload
  if [ "$enable" = 1 ]; then
    systemctl enable --now agvslamd
    systemctl --no-pager status agvslamd || true
  else
    echo "install.sh: start with: systemctl enable --now agvslamd"
  fi
else
  echo "install.sh: systemd is not running here; the unit is installed for the next boot"
fi
"$bindir/agvslamd" --config "$etc/agvslamd.yaml" --check >/dev/null 2>&1 &&
  echo "install.sh: /etc/agvslam/agvslamd.yaml passes --check" ||
  echo "install.sh: /etc/agvslam/agvslamd.yaml does not pass --check yet: agvslamd --config /etc/agvslam/agvslamd.yaml --check"
