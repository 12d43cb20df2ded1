# VM case: wheel odometry in over a real (virtual) CAN bus and the daemon's live odometry check. agvslamd plays a
# simulator sequence (scene2, seed 11, 80 frames, the daemon tests' sequence) slowed down to what the emulated VM
# tracks (source.rate 0.02: one frame per 2.5 s), with odometry.source can on vcan0; can_odometry_send plays the
# simulator's wheel odometry (odometry.txt: the true motion with its +1 % bias) as VEHICLE_ODOMETRY frames in step
# with the playback (speeds slowed down alike), from dataset time 2.0 s on scaled by 0.75 (the pose then runs 33 %
# longer than the odometry). candump records the bus. Pass only if
#   - agvslamd read the odometry frames (none rejected) and stops cleanly on SIGTERM;
#   - AGVSLAM_ODOM_CHECK frames (decoded with deploy/agvslam.dbc by agvslam-can-decode, Crc right) say Agrees
#     while the odometry is true, with a distance ratio within 0.8..1.2, and Disagrees once the scaled odometry
#     fills the window, with a ratio above 1.2;
#   - the daemon logged the warning when the state turned to disagrees.
# Windows are 30 s of wall time (0.6 s of the sequence, about 2 m driven). Takes ~4-5 min on the 2-core machine.
. "$(dirname "$0")/lib.sh"
for t in agvslamd agvslam-can-decode can_odometry_send; do require_tool "$t"; done
w=$VM_LOG_DIR
dbc=$AGVSLAM_SOURCE/deploy/agvslam.dbc
params=$AGVSLAM_SOURCE/params
rate=0.02

step "the simulator sequence"
seq=$AGVSLAM_BUILD/test-data/daemon_scene2_s11_80
if [ ! -f "$seq/odometry.txt" ]; then
  # The same command as tests/daemon/daemon_test_util.h (the host's daemon tests usually rendered it already).
  "$BIN/agvslam-sim" --scenario scene2 --seed 11 --frames 80 --threads 2 --out "$w/seq" >"$w/sim.log" 2>&1 ||
    die "agvslam-sim failed: $(tail -3 "$w/sim.log")"
  seq=$w/seq
fi
echo "sequence: $seq"

step "kernel: vcan0"
modprobe vcan && modprobe can-raw || die "modprobe vcan can-raw"
ip link add dev vcan0 type vcan && ip link set vcan0 up || die "vcan0"
candump -L vcan0 >"$w/can.log" 2>"$w/can.err" &
dump=$!

cat >"$w/agvslamd.yaml" <<EOF
source:
  type: dataset
  dataset: $seq
  rate: $rate
calibration:
  file: ""
stages:
  features: $params/features.yaml
  slam: $params/slam.yaml
  place: ""
pipeline:
  dynamic: off
  mapping: thread
  heartbeat_ms: 5000
base_link:
  z_m: 0.5
dds:
  enabled: false
can:
  enabled: true
  interface: vcan0
  rate_hz: 0
odometry:
  source: can
  window_s: 30              # wall s: 0.6 s of the sequence at rate $rate
  min_distance_m: 0.5
  min_yaw_rate_degps: 0.5   # a straight aisle: heading judged against 0.2 x 15 deg
  stale_ms: 1000
  warn_every_s: 0
can_odometry:
  dbc: $dbc
log:
  pose_log: $w/poses.jsonl
  stats_every_s: 20
EOF

step "agvslamd and the odometry sender"
"$BIN/agvslamd" --config "$w/agvslamd.yaml" --json "$w/stats.json" >"$w/daemon.out" 2>"$w/daemon.err" &
daemon=$!
"$BIN/can_odometry_send" --interface vcan0 --odometry "$seq/odometry.txt" --dbc "$dbc" --pose-log "$w/poses.jsonl" \
  --rate $rate --scale 0.75 --scale-from-s 2.0 2>"$w/sender.err" &
sender=$!
wait $sender || die "can_odometry_send failed: $(tail -3 "$w/sender.err")"
cat "$w/sender.err"
i=0
while kill -0 $daemon 2>/dev/null; do  # the dataset ends shortly after the odometry
  i=$((i + 1)); [ $i -le 600 ] || { kill -TERM $daemon; break; }
  sleep 0.1
done
wait $daemon; rc=$?
kill $dump 2>/dev/null; wait $dump 2>/dev/null
grep -E "odometry|status:" "$w/daemon.err" | tail -8
[ $rc -eq 0 ] || die "agvslamd exited $rc: $(tail -5 "$w/daemon.err")"

step "the bus: AGVSLAM_ODOM_CHECK decoded with the DBC"
"$BIN/agvslam-can-decode" --dbc "$dbc" --log "$w/can.log" --json >"$w/decoded.jsonl" || die "agvslam-can-decode failed"
tail -1 "$w/decoded.jsonl"
python3 - "$w/decoded.jsonl" "$w/stats.json" <<'PY' || die "odometry check on the bus"
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
summary = rows[-1]["summary"]
assert summary["crc_bad"] == 0, summary
checks = [r for r in rows if r.get("message") == "AGVSLAM_ODOM_CHECK"]
odo = [r for r in rows if r.get("message") == "VEHICLE_ODOMETRY"]
states = [int(r["signals"]["OdomCheckState"]) for r in checks]
print(f"{len(odo)} VEHICLE_ODOMETRY frames, {len(checks)} AGVSLAM_ODOM_CHECK frames; states in order:",
      [s for i, s in enumerate(states) if i == 0 or s != states[i - 1]])
agree = [r["signals"]["DistanceRatio"] for r in checks if int(r["signals"]["OdomCheckState"]) == 4]
disagree = [r["signals"]["DistanceRatio"] for r in checks if int(r["signals"]["OdomCheckState"]) == 5]
assert agree, "no ODOM_CHECK frame in the Agrees state"
assert disagree, "no ODOM_CHECK frame in the Disagrees state"
print(f"agrees: {len(agree)} frames, distance ratio {min(agree):.3f}..{max(agree):.3f}")
print(f"disagrees: {len(disagree)} frames, distance ratio {min(disagree):.3f}..{max(disagree):.3f}")
assert all(0.8 <= r <= 1.2 for r in agree), agree
assert max(disagree) > 1.2, disagree
first_disagree = states.index(5)
assert 4 in states[:first_disagree], "Agrees must come before Disagrees (the odometry is scaled only later)"
stats = json.load(open(sys.argv[2]))["odometry"]
print("daemon:", stats)
assert stats["can_frames"] > 0 and stats["crc_bad"] == 0 and stats["counter_repeated"] == 0, stats
assert stats["disagreements"] >= 1, stats
PY
grep -q "odometry: the pose disagrees with the wheel odometry" "$w/daemon.err" || die "no warning in the daemon's log"
echo "PASS: odometry in over vcan0; AGVSLAM_ODOM_CHECK agrees with the true odometry and disagrees with the scaled one"
