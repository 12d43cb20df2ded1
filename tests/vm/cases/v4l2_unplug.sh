# VM case: the camera disappears mid-run and comes back. The feeder plays frames 0:25 and stops; the driver
# reports the stall and closes; v4l2loopback is removed (rmmod: the device nodes vanish, reopening fails with
# ENOENT and backs off); the module is loaded again and a second feeder plays frames 25:60. agvslam-camera keeps
# running throughout and must receive all 60 frames pixel-exact and in order, with one loss and one reopen.
. "$(dirname "$0")/lib.sh"
require_tool agvslam-v4l2-feed; require_tool agvslam-camera
data=$(require_data data/euroc_v101_f000-094) || exit $?
rate=${RATE_HZ:-10}
w=$VM_LOG_DIR
load() { modprobe v4l2loopback devices=2 video_nr=10,11 card_label=left,right max_buffers=8 || die "modprobe v4l2loopback"; }

"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 25:60 --manifest "$w/manifest2.txt" --dry-run || die "manifest 2"
step "load v4l2loopback, feeder 1: frames 0:25"
load
"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 0:25 --left /dev/video10 --right /dev/video11 --rate-hz "$rate" \
  --manifest "$w/manifest1.txt" --wait-file "$w/ready" --wait-timeout-s 120 &
feeder=$!
wait_for "$w/manifest1.txt" 180 || die "feeder 1 wrote no manifest"
"$BIN/agvslam-camera" --left /dev/video10 --right /dev/video11 --width 752 --height 480 --fps 0 --tolerance-ms 5 \
  --stall-ms 1500 --backoff-ms 100:1000 --wait --ready-file "$w/ready" --expect-manifest "$w/manifest1.txt" \
  --expect-manifest "$w/manifest2.txt" --min-losses 1 --timeout-s 180 --json "$w/camera.json" &
camera=$!
wait $feeder || die "feeder 1 failed"

step "unplug: rmmod v4l2loopback (retried until the reader has closed after its stall)"
i=0
until rmmod v4l2loopback 2>/dev/null; do
  i=$((i + 1)); [ $i -le 200 ] || die "rmmod v4l2loopback kept failing"
  sleep 0.1
done
[ ! -e /dev/video10 ] || die "/dev/video10 still there after rmmod"
echo "v4l2loopback removed after $i retries; device nodes gone"
rm -f "$w/ready"
sleep 3  # the driver keeps retrying (ENOENT) with back-off

step "replug: modprobe v4l2loopback, feeder 2: frames 25:60"
load
"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 25:60 --left /dev/video10 --right /dev/video11 --rate-hz "$rate" \
  --wait-file "$w/ready" --wait-timeout-s 120 || die "feeder 2 failed"
wait $camera || die "agvslam-camera did not get every frame back in order after the unplug"
cat "$w/camera.json"
grep -q '"reopens": 1' "$w/camera.json" || die "expected exactly one reopen"
echo "PASS: loss reported, device reopened, all 60 frames pixel-exact and in order"
