# VM case: the MJPEG path. agvslam-v4l2-feed encodes KITTI 06 frames 0:20 (1226x370 cropped to 1216x368, as
# libv4lconvert needs multiples of 16; a moving car: consecutive frames differ a lot) as JPEG (quality 90) and queues one JPEG per buffer into two v4l2loopback devices, as a
# UVC camera sends MJPEG; the driver decodes them with libv4lconvert and takes the Y plane. agvslam-camera checks
# every pair against its dataset frame within a mean absolute error of 3 grey levels (JPEG loss measured 1.7-1.8; a wrong or
# shifted frame is tens of levels off), in order, none unpaired.
. "$(dirname "$0")/lib.sh"
require_tool agvslam-v4l2-feed; require_tool agvslam-camera
data=$(require_data data/kitti06_f000-050) || exit $?
rate=${RATE_HZ:-5}
w=$VM_LOG_DIR
step "modprobe v4l2loopback"
modprobe v4l2loopback devices=2 video_nr=10,11 card_label=left,right max_buffers=8 || die "modprobe v4l2loopback"
step "feeder: KITTI 06 frames 0:20 as MJPEG at $rate Hz"
"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 0:20 --format mjpeg --jpeg-quality 90 --left /dev/video10 \
  --right /dev/video11 --rate-hz "$rate" --wait-file "$w/ready" --wait-timeout-s 180 --json "$w/feed.json" &
feeder=$!
"$BIN/agvslam-camera" --left /dev/video10 --right /dev/video11 --width 1216 --height 368 --format mjpeg --fps 0 \
  --tolerance-ms 5 --wait --ready-file "$w/ready" --expect-dataset "$data" --expect-frames 0:20 \
  --max-mean-abs-error 3 --timeout-s 180 --json "$w/camera.json" || die "agvslam-camera (MJPEG)"
wait $feeder || die "the feeder failed"
grep -q '"unpaired_left": 0' "$w/camera.json" && grep -q '"unpaired_right": 0' "$w/camera.json" || die "unpaired frames"
grep -q '"corrupt": 0' "$w/camera.json" || die "corrupt frames"
echo "PASS: 20 MJPEG pairs decoded by libv4lconvert, each within 3 grey levels of its own frame"
