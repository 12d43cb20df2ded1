# VM case: agvslamd end to end on real kernel drivers. agvslam-v4l2-feed plays the real KITTI 06 excerpt
# (frames 0:20, 1226x370 grey, rectified) into two v4l2loopback devices; agvslamd reads them over V4L2 (pairing by
# time stamp), tracks, and publishes over DDS (lo) to agvslam-echo and over CAN on vcan0 to candump. Mid-run:
# `ip link set vcan0 down` / `up` while frames are processed, then the camera is unplugged (feeder 1 stops after
# frame 9, the daemon reports the stall and closes, `rmmod v4l2loopback` removes the nodes, reopening fails with
# back-off, `modprobe` brings them back) and feeder 2 plays frames 10:20. Pass only if
#   - the daemon survives both and stops cleanly on SIGTERM (exit 0), having lost one camera and reopened it;
#   - DDS: agvslam-echo got a pose for every frame the daemon tracked and a status for every sample (heartbeats in
#     the outage included), in order, with the values the daemon logged;
#   - CAN: every cycle the daemon says it sent is on the bus in order, decoded with deploy/agvslam.dbc (can_log_check:
#     values within half a step, Crc, Counter), with an outage and a resumption;
#   - the published poses agree with agvslam-run's trajectory on the same frames (run here after the daemon).
# The emulated VM runs the SLAM ~50-80x slower than the host (TCG emulating the SIMD kernels: ~1.6 s of tracking a
# KITTI frame), so the feeder plays at RATE_HZ (default 0.5) and the daemon runs without the dynamic detector
# (the detector path is tested on the host: tests/daemon/test_agvslamd.cpp) and with local mapping in its own
# thread, as on a vehicle. Takes ~2.5 min on the 2-core machine.
. "$(dirname "$0")/lib.sh"
for t in agvslamd agvslam-v4l2-feed agvslam-echo agvslam-run agvslam-can-decode can_log_check; do require_tool "$t"; done
data=$(require_data data/kitti06_f000-050) || exit $?
rate=${RATE_HZ:-0.5}
w=$VM_LOG_DIR
dbc=$AGVSLAM_SOURCE/deploy/agvslam.dbc
params=$AGVSLAM_SOURCE/params
load() { modprobe v4l2loopback devices=2 video_nr=10,11 card_label=left,right max_buffers=8 || die "modprobe v4l2loopback"; }
# wait_log PATTERN COUNT SECONDS: until the daemon's log has COUNT lines matching PATTERN.
wait_log() {
  local i=0
  until [ "$(grep -c -- "$1" "$w/daemon.err" 2>/dev/null || echo 0)" -ge "$2" ]; do
    i=$((i + 1)); [ $i -le $(($3 * 10)) ] || die "agvslamd did not log '$1' within $3 s: $(tail -3 "$w/daemon.err")"
    kill -0 "$daemon" 2>/dev/null || die "agvslamd died: $(tail -5 "$w/daemon.err")"
    sleep 0.1
  done
}
# samples PATTERN: pose-log lines matching PATTERN so far.
samples() { grep -c -- "$1" "$w/poses.jsonl" 2>/dev/null || echo 0; }

step "kernel: v4l2loopback (2 cameras), vcan0, lo"
ip link set lo up
load
modprobe vcan && modprobe can-raw || die "modprobe vcan can-raw"
ip link add dev vcan0 type vcan && ip link set vcan0 up || die "vcan0"
candump -L any >"$w/can.log" 2>"$w/can.err" &
dump=$!

cat >"$w/agvslamd.yaml" <<EOF
source:
  type: v4l2
  wait_for_camera: true
camera:
  left_device: /dev/video10
  right_device: /dev/video11
  width: 1226
  height: 370
  pixel_format: grey
  fps: 0
  pair_tolerance_ms: 5
  stall_timeout_ms: 4000          # > the 2 s frame period of this test
  reopen_backoff_initial_ms: 100
  reopen_backoff_max_ms: 1000
calibration:
  file: $data/calib.txt
stages:
  features: $params/features_kitti.yaml
  slam: $params/slam.yaml
  place: $params/place.yaml
pipeline:
  dynamic: off
  mapping: thread
  frame_rate_hz: 10               # KITTI's camera rate (keyframe spacing), as agvslam-run takes from times.txt
  heartbeat_ms: 3000              # > the frame period: heartbeats only while the camera is gone
base_link:
  z_m: 1.65                       # KITTI's camera height above the road
dds:
  network_interface: lo
  topic_namespace: agvslam
  wait_for_subscribers: 1
  wait_timeout_s: 120
can:
  enabled: true
  interface: vcan0
  rate_hz: 0                      # a cycle for every sample
  reopen_min_ms: 100
  reopen_max_ms: 500
trajectory:
  file: $w/trajectory_camera.tum
  frame: camera
  flush_every: 1
log:
  pose_log: $w/poses.jsonl
  stats_every_s: 5
EOF

"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 10:20 --manifest "$w/manifest2.txt" --dry-run >/dev/null 2>&1 || die "manifest 2"
step "feeder 1: frames 0:10 at $rate Hz"
"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 0:10 --left /dev/video10 --right /dev/video11 --rate-hz "$rate" \
  --manifest "$w/manifest1.txt" --wait-file "$w/ready1" --wait-timeout-s 180 >"$w/feed1.out" 2>"$w/feed1.err" &
feeder=$!
wait_for "$w/manifest1.txt" 180 || die "feeder 1 wrote no manifest"
sleep 1

step "agvslam-echo (DDS on lo) and agvslamd"
"$BIN/agvslam-echo" --json --interface lo --namespace agvslam --timeout 900 >"$w/echo.jsonl" 2>"$w/echo.err" &
echo_pid=$!
"$BIN/agvslamd" --config "$w/agvslamd.yaml" --json "$w/stats.json" >"$w/daemon.out" 2>"$w/daemon.err" &
daemon=$!
wait_log "subscriber(s) on every topic matched; capturing" 1 120
touch "$w/ready1"
echo "agvslamd streaming at t=$(cut -d' ' -f1 /proc/uptime)"

step "CAN: vcan0 down and up while frames are processed"
i=0
until [ "$(samples '"sent":true')" -ge 3 ]; do
  i=$((i + 1)); [ $i -le 1200 ] || die "no CAN cycle sent within 120 s: $(tail -3 "$w/daemon.err")"
  sleep 0.1
done
ip link set vcan0 down || die "ip link set vcan0 down"
echo "vcan0 down at t=$(cut -d' ' -f1 /proc/uptime) after $(samples '"i"') samples"
sleep 4.5  # two frame periods: at least one cycle cannot be sent
ip link set vcan0 up || die "ip link set vcan0 up"
echo "vcan0 up at t=$(cut -d' ' -f1 /proc/uptime) after $(samples '"i"') samples"
wait $feeder || die "feeder 1 failed: $(tail -3 "$w/feed1.err")"

step "camera unplug: the daemon reports the stall and closes; rmmod v4l2loopback"
wait_log "camera: lost" 1 60
i=0
until rmmod v4l2loopback 2>/dev/null; do
  i=$((i + 1)); [ $i -le 300 ] || die "rmmod v4l2loopback kept failing"
  sleep 0.1
done
[ ! -e /dev/video10 ] || die "/dev/video10 still there after rmmod"
echo "v4l2loopback removed after $i retries at t=$(cut -d' ' -f1 /proc/uptime)"
sleep 4  # reopening fails (ENOENT) with back-off; heartbeats (state lost) keep going on DDS and CAN
kill -0 $daemon || die "agvslamd died while the camera was gone"

step "replug: modprobe v4l2loopback, feeder 2: frames 10:20"
load
"$BIN/agvslam-v4l2-feed" --dataset "$data" --frames 10:20 --left /dev/video10 --right /dev/video11 --rate-hz "$rate" \
  --wait-file "$w/ready2" --wait-timeout-s 180 >"$w/feed2.out" 2>"$w/feed2.err" &
feeder=$!
wait_log "camera: streaming again" 1 60
touch "$w/ready2"
wait $feeder || die "feeder 2 failed: $(tail -3 "$w/feed2.err")"
# Let the daemon finish the last frame (its tracking takes ~1-3 s here), then stop it.
last=-1
until [ "$(samples '"heartbeat":false')" = "$last" ]; do last=$(samples '"heartbeat":false'); sleep 4; done

step "SIGTERM: clean stop"
kill -TERM $daemon
wait $daemon || die "agvslamd exited with $? after SIGTERM: $(tail -5 "$w/daemon.err")"
sleep 1
kill -INT $echo_pid; wait $echo_pid
kill $dump; wait $dump 2>/dev/null
grep -E "stopping|stopped|lost|streaming again|can:" "$w/daemon.err" | tail -8
cat "$w/stats.json"

step "offline runner on the same frames"
"$BIN/agvslam-run" --dataset "$data" --frames 0:19 --out "$w/runner.tum" --dynamic off --mapping inline \
  --params-slam "$params/slam.yaml" --params-features "$params/features_kitti.yaml" --json "$w/runner.json" \
  >"$w/runner.out" 2>"$w/runner.err" || die "agvslam-run failed: $(tail -3 "$w/runner.err")"
head -2 "$w/runner.out"

step "CAN: the bus against what the daemon logged (deploy/agvslam.dbc)"
"$BIN/can_log_check" --dbc "$dbc" --log "$w/can.log" --sent "$w/poses.jsonl" --expect-outage ||
  die "CAN: the bus does not carry what agvslamd sent"
"$BIN/agvslam-can-decode" --dbc "$dbc" --log "$w/can.log" --json >"$w/can_decoded.jsonl" || die "agvslam-can-decode"
tail -1 "$w/can_decoded.jsonl"
grep -q '"crc_bad":0' "$w/can_decoded.jsonl" || die "CRC errors on the bus"

step "DDS, the camera loss and the runner"
python3 - "$w" <<'PY' || die "DDS / runner checks failed"
import json, math, sys
w = sys.argv[1]
def lines(p): return [json.loads(l) for l in open(p) if l.startswith("{")]
log = lines(w + "/poses.jsonl")
echo = [l for l in lines(w + "/echo.jsonl") if "topic" in l]
stats = json.load(open(w + "/stats.json"))
fail = []
def stamp(m): return m["header"]["stamp"]["sec"] * 10**9 + m["header"]["stamp"]["nanosec"]
frames = [l for l in log if not l["heartbeat"]]
tracked = [l for l in log if l["dds"]["pose"]]
poses = [l["msg"] for l in echo if l["topic"] == "pose"]
status = [l["msg"] for l in echo if l["topic"] == "status"]
# Every frame fed was processed, or counted as dropped; the camera was lost once and reopened.
if stats["processed"] + stats["dropped_queue"] + stats["dropped_source"] != 20:
    fail.append("processed %d + dropped %d + %d != 20 frames fed" % (stats["processed"], stats["dropped_queue"], stats["dropped_source"]))
if stats["source"]["losses"] < 1 or stats["source"]["reopens"] < 1:
    fail.append("expected a camera loss and a reopen: %s" % stats["source"])
if stats["stop_reason"] != "SIGTERM": fail.append("stop reason " + stats["stop_reason"])
# DDS: a pose for every tracked frame, a status for every sample, in order, with the logged values.
if [stamp(m) for m in poses] != [l["t_ns"] for l in tracked]:
    fail.append("DDS poses (%d) are not the tracked samples (%d) in order" % (len(poses), len(tracked)))
for m, l in zip(poses, tracked):
    p, t = m["pose"]["pose"]["position"], l["sample"]["t"]
    if [p["x"], p["y"], p["z"]] != t: fail.append("pose at %d differs from the log" % l["t_ns"]); break
if [stamp(m) for m in status] != [l["t_ns"] for l in log] or [m["tracking_state"] for m in status] != [l["sample"]["tracking_state"] for l in log]:
    fail.append("DDS status (%d) is not every sample (%d) in order" % (len(status), len(log)))
# While the camera was gone: heartbeats saying lost. (Before the first frame went through, a heartbeat says "not
# initialised" (0): the emulated VM may take longer than heartbeat_ms over the first frame.)
first_frame = next((i for i, l in enumerate(log) if not l["heartbeat"]), len(log))
hb = [l for l in log[first_frame:] if l["heartbeat"]]
if any(l["sample"]["tracking_state"] != 0 for l in log[:first_frame]): fail.append("a heartbeat before the first frame is not 'not initialised'")
if not hb or any(l["sample"]["tracking_state"] != 3 for l in hb): fail.append("expected heartbeats with state lost during the outage")
# Against the offline runner (same frames, same settings but inline mapping): the camera trajectory the daemon
# published, frame by frame. The daemon's frame_index counts delivered pairs = the dataset frame (none lost by the
# source). Tolerance 0.15 m (0.7 % of the 22.7 m driven): agvslam-run with threaded mapping ends 2.2 cm from its
# inline run on these frames on the host; here mapping lags tracking by several frames (each keyframe takes
# ~2.5 s of local BA in the emulated VM), and frames dropped by a slow step change the track.
run = {f["frame"]: f["p_w_c"] for f in json.load(open(w + "/runner.json"))["per_frame"] if f["p_w_c"]}
traj = {}
for line in open(w + "/trajectory_camera.tum"):
    if line.startswith("#"): continue
    v = line.split(); s, ns = v[0].split(".")
    traj[int(s) * 10**9 + int(ns)] = [float(x) for x in v[1:4]]
worst, n = 0.0, 0
for l in tracked:
    i = l["sample"]["frame_index"]
    if i in run and l["t_ns"] in traj:
        worst = max(worst, math.dist(traj[l["t_ns"]], run[i])); n += 1
if stats["dropped_source"] != 0: fail.append("the source lost frames: the frame index mapping does not hold")
if n < 12: fail.append("only %d poses compared with the runner" % n)
if worst > 0.15: fail.append("published poses %.3f m from agvslam-run's" % worst)
print("frames: %d processed, %d dropped (queue), %d tracked; DDS %d poses, %d status (%d heartbeats); camera losses %d, reopens %d; "
      "runner agreement: %d poses, max %.4f m; latency median %.0f ms (emulated)" %
      (stats["processed"], stats["dropped_queue"], stats["tracked"], len(poses), len(status), len(hb),
       stats["source"]["losses"], stats["source"]["reopens"], n, worst, stats["latency_ms"]["median"]))
for f in fail: print("FAIL:", f)
sys.exit(1 if fail else 0)
PY
echo "PASS: agvslamd over V4L2 -> DDS + CAN; every processed frame on both outputs in order; vcan0 down/up and camera unplug survived; agrees with agvslam-run"
