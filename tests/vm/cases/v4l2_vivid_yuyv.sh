# VM case: the driver on a real kernel capture driver, vivid (the V4L2 reference test driver): YUYV from its
# webcam input, 640x480 split side by side into two 320x480 eyes. vivid stamps buffers CLOCK_MONOTONIC (flagged)
# and numbers them, like UVC. Its default 75% colour-bar pattern checks the YUYV luma path and the split: the
# left half (white, yellow, cyan, green bars, with vivid's text overlay) has mean luma ~125, the right half
# (magenta, red, blue, black) ~48; chroma bytes or swapped halves would not give bright-left / dark-right.
# (vivid stamps a frame with its nominal end-of-frame time when it generates it, a period ahead of delivery in
# the slow VM, so capture latency is not checked here.)
. "$(dirname "$0")/lib.sh"
require_tool agvslam-camera
step "modprobe vivid (one video capture node)"
modprobe vivid n_devs=1 node_types=0x1 || die "modprobe vivid"
dev=""
for n in /sys/class/video4linux/video*; do
  [ "$(cat "$n/name")" = "vivid-000-vid-cap" ] && dev=/dev/$(basename "$n")
done
[ -n "$dev" ] || die "no vivid capture node"
v4l2-ctl -d "$dev" --get-fmt-video | head -8
step "capture 30 pairs, YUYV, side by side from $dev"
"$BIN/agvslam-camera" --side-by-side --left "$dev" --width 320 --height 480 --format yuyv --fps 0 --frames 30 \
  --timeout-s 120 --json "$VM_LOG_DIR/vivid.json" || die "agvslam-camera on vivid"
cat "$VM_LOG_DIR/vivid.json"
/usr/bin/python3 - "$VM_LOG_DIR/vivid.json" <<'PY' || die "vivid content or counters wrong"
import json, sys
j = json.load(open(sys.argv[1]))
l, r = j["last_left_mean"], j["last_right_mean"]
print(f"left mean luma {l:.1f} (expect ~125), right {r:.1f} (expect ~48), dropped {j['dropped_left']}, corrupt {j['corrupt']}")
assert 105 < l < 160 and 35 < r < 65 and l - r > 50, "colour-bar luma not where YUYV's Y bytes put it"
assert j["frames"] == 30 and j["corrupt"] == 0
PY
echo "PASS: vivid YUYV side by side: 30 pairs, luma and halves right"
