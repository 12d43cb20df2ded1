# VM case: agvslam-v4l2-feed plays the real EuRoC V1_01 excerpt (rectified, 752x480 grey) into two v4l2loopback
# devices; agvslam-camera reads them through the V4L2 driver (libv4l2, mmap, poll, time-stamp pairing) and checks
# every frame arrived pixel-exact, in order, left with its own right. Then the same through one side-by-side
# device, and the driver's errors for a wrong format, a refused size and a device that is not V4L2.
# RATE_HZ (default 10: the emulated VM under a loaded 2-core host sustains it with margin; 20 passed when the host was quiet) and FRAMES (default all) can be set in the environment. The feeder
# queues both eyes with one capture time stamp (--stamp queue, like a hardware-triggered pair): write() stamps
# would carry the emulated VM's scheduling jitter (up to ~50 ms between two writes was seen under load).
. "$(dirname "$0")/lib.sh"
require_tool agvslam-v4l2-feed; require_tool agvslam-camera
data=$(require_data data/euroc_v101_f000-094) || exit $?
rate=${RATE_HZ:-10}
frames=${FRAMES:-0:95}
w=$VM_LOG_DIR

step "modprobe v4l2loopback (3 devices)"
modprobe v4l2loopback devices=3 video_nr=10,11,12 card_label=left,right,sbs max_buffers=8 || die "modprobe v4l2loopback"
ls -l /dev/video1*

step "feeder: $frames at $rate Hz into /dev/video10 + /dev/video11"
"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames "$frames" --left /dev/video10 --right /dev/video11 --rate-hz "$rate" \
  --manifest "$w/manifest.txt" --wait-file "$w/ready" --wait-timeout-s 120 --json "$w/feed.json" &
feeder=$!
wait_for "$w/manifest.txt" 180 || die "the feeder wrote no manifest"
sleep 1  # the feeder announces the devices right after the manifest

step "configuration errors are clear and exit 2"
expect_exit 2 "does not offer pixel format YUYV" -- "$BIN/agvslam-camera" --left /dev/video10 --right /dev/video11 --format yuyv --frames 1 --timeout-s 5
expect_exit 2 "refused size 640x480" -- "$BIN/agvslam-camera" --left /dev/video10 --right /dev/video11 --width 640 --height 480 --frames 1 --timeout-s 5
expect_exit 2 "is not a V4L2 device" -- "$BIN/agvslam-camera" --left /dev/null --right /dev/video11 --frames 1 --timeout-s 5
expect_exit 1 "No such file or directory" -- "$BIN/agvslam-camera" --left /dev/video19 --right /dev/video11 --frames 1 --timeout-s 5

step "capture: two devices paired by time stamp"
"$BIN/agvslam-camera" --left /dev/video10 --right /dev/video11 --width 752 --height 480 --format grey --fps 0 \
  --tolerance-ms 5 --wait --ready-file "$w/ready" --expect-manifest "$w/manifest.txt" --timeout-s 120 \
  --json "$w/camera.json" || die "agvslam-camera (two devices)"
wait $feeder || die "the feeder failed"
cat "$w/feed.json" "$w/camera.json"
grep -q '"unpaired_left": 0' "$w/camera.json" && grep -q '"unpaired_right": 0' "$w/camera.json" || die "frames were left unpaired"

step "side by side: frames 0:20 at $rate Hz into /dev/video12 (1504x480)"
"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 0:20 --side-by-side --left /dev/video12 --rate-hz "$rate" \
  --manifest "$w/manifest_sbs.txt" --wait-file "$w/ready_sbs" --wait-timeout-s 120 &
feeder=$!
wait_for "$w/manifest_sbs.txt" 180 || die "the feeder wrote no manifest"
"$BIN/agvslam-camera" --side-by-side --left /dev/video12 --width 752 --height 480 --fps 0 --wait \
  --ready-file "$w/ready_sbs" --expect-manifest "$w/manifest_sbs.txt" --timeout-s 120 --json "$w/camera_sbs.json" ||
  die "agvslam-camera (side by side)"
wait $feeder || die "the side-by-side feeder failed"
echo "PASS: every frame arrived pixel-exact and in order, over two devices and side by side"
