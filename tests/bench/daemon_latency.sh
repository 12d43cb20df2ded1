#!/usr/bin/env bash
# agvslamd capture-to-publish latency and delivered rate on the host, with the dataset source playing a simulator
# sequence (752x480 grey at 20 Hz) like a camera: frame k is decoded ahead and released at its due time, stamped
# with CLOCK_REALTIME at release. Pipeline as on a vehicle: detector one frame ahead, tracking, local mapping in
# its own thread, outputs thread; DDS on loopback to agvslam-echo in a private network namespace.
#
#   tests/bench/daemon_latency.sh [--build DIR] [--scenario scene4] [--frames 400] [--seed 1] [--rt] [--out DIR]
#                                 [--record]
#
# --rt runs agvslamd under SCHED_FIFO (chrt -f 10), as a vehicle computer would give the daemon its cores, so other
# jobs on a shared build machine do not stand in its way; without it the figures are upper bounds under whatever
# else runs. Reports (and writes OUT/summary.json):
#   delivered rate   poses received by the echo / play time, frames processed vs captured (every frame published?)
#   latency          capture -> sample handed to the outputs (the daemon's latency_ns, also on the status topic),
#                    and capture -> received by agvslam-echo (header.stamp -> receive), median / p99 / max
#   stages           per-frame wall and thread-CPU time of the detector and tracking, queue waits (median / p99)
# The rendered sequence is cached in BUILD/bench-data. Needs `unshare -n` (root or user namespaces).
set -euo pipefail
source "$(dirname "$0")/record.sh"
source "$(dirname "$0")/agvslamd_sim.sh"
record_init "$0" "$@"
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/../.." && pwd)
build=$src/build/release
scenario=scene4
frames=400
seed=1
rt=0
out=""
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$(cd "$2" && pwd); shift 2 ;;
    --scenario) scenario=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --rt) rt=1; shift ;;
    --record) record=1; shift ;;
    --out) out=$2; shift 2 ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "daemon_latency.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
bin=$build/bin
for t in agvslamd agvslam-echo agvslam-sim; do
  [ -x "$bin/$t" ] || { echo "daemon_latency.sh: $bin/$t not built" >&2; exit 2; }
done
out=${out:-$(mktemp -d /tmp/agvslamd-latency.XXXXXX)}
mkdir -p "$out"
seq=$build/bench-data/${scenario}_s${seed}_${frames}
if [ ! -f "$seq/.complete" ]; then
  echo "daemon_latency.sh: rendering $scenario seed $seed, $frames frames -> $seq"
  rm -rf "$seq"
  "$bin/agvslam-sim" --scenario "$scenario" --seed "$seed" --frames "$frames" --threads 2 --out "$seq" >/dev/null
  touch "$seq/.complete"
fi
ns="unshare -n"
unshare -n true 2>/dev/null || ns="unshare -rn"
prio=""
[ "$rt" = 1 ] && prio="chrt -f 10"

cat >"$out/agvslamd.yaml" <<EOF
source:
  type: dataset
  dataset: $seq
  rate: 1
$(agvslamd_sim_pipeline_yaml "$src")
dds:
  network_interface: lo
  topic_namespace: agvslam_bench
  wait_for_subscribers: 1
  wait_timeout_s: 60
log:
  pose_log: $out/poses.jsonl
  stats_every_s: 0
EOF

cat >"$out/run.sh" <<EOF
ip link set lo up
$bin/agvslam-echo --json --interface lo --namespace agvslam_bench --topic pose --timeout 600 \
  --summary $out/echo_summary.json > $out/echo.jsonl 2> $out/echo.err &
e=\$!
$prio $bin/agvslamd --config $out/agvslamd.yaml --json $out/stats.json > $out/daemon.out 2> $out/daemon.err
rc=\$?
sleep 1
kill -INT \$e
wait \$e
exit \$rc
EOF
echo "daemon_latency.sh: $scenario seed $seed, $frames frames at 20 Hz$([ "$rt" = 1 ] && echo ', agvslamd under SCHED_FIFO'); logs in $out"
load_before=$(cut -d' ' -f1 /proc/loadavg)
$ns sh "$out/run.sh"
load_after=$(cut -d' ' -f1 /proc/loadavg)

record_start
python3 - "$out" "$frames" "$rt" "$load_before" "$load_after" <<'EOF'
import json, sys
out, frames, rt, load_before, load_after = sys.argv[1], int(sys.argv[2]), sys.argv[3] == "1", sys.argv[4], sys.argv[5]

def q(v, p):
    if not v: return 0.0
    s = sorted(v)
    return s[min(len(s) - 1, int(p * (len(s) - 1) + 0.5))]

log = [json.loads(l) for l in open(out + "/poses.jsonl") if l.startswith("{")]
frames_log = [l for l in log if not l["heartbeat"]]
echo = [json.loads(l) for l in open(out + "/echo.jsonl") if l.startswith("{") and '"topic"' in l]
stats = json.load(open(out + "/stats.json"))
tracked = [l for l in frames_log if l["dds"]["pose"]]
stamps_sent = [l["t_ns"] for l in tracked]
stamps_recv = [m["msg"]["header"]["stamp"]["sec"] * 10**9 + m["msg"]["header"]["stamp"]["nanosec"] for m in echo]
in_order = stamps_recv == sorted(stamps_recv)
handover_ms = [l["sample"]["latency_ns"] * 1e-6 for l in frames_log]
receive_ms = [(m["recv_t_ns"] - s) * 1e-6 for m, s in zip(echo, stamps_recv)]
play_s = (frames_log[-1]["t_ns"] - frames_log[0]["t_ns"]) * 1e-9 if len(frames_log) > 1 else 0
rate = (len(echo) - 1) / play_s if play_s > 0 else 0
stage = {}
for k in ["capture_queue", "detector", "detector_cpu", "detected_queue", "tracking", "tracking_cpu", "output_queue"]:
    v = [l["times_ms"][k] for l in frames_log if l["times_ms"][k] >= 0]
    stage[k] = {"median": q(v, 0.5), "p99": q(v, 0.99)}
summary = {
    "frames_in_sequence": frames,
    "captured": stats["captured"], "processed": stats["processed"], "dropped_queue": stats["dropped_queue"],
    "tracked": stats["tracked"], "poses_received": len(echo), "poses_published": len(tracked),
    "every_tracked_pose_received_in_order": in_order and stamps_recv == stamps_sent,
    "delivered_rate_hz": rate,
    "latency_capture_to_outputs_ms": {"median": q(handover_ms, 0.5), "p99": q(handover_ms, 0.99), "max": max(handover_ms)},
    "latency_capture_to_receive_ms": {"median": q(receive_ms, 0.5), "p99": q(receive_ms, 0.99), "max": max(receive_ms) if receive_ms else 0},
    "stages_ms": stage, "sched_fifo": rt, "loadavg_before_after": [load_before, load_after],
}
json.dump(summary, open(out + "/summary.json", "w"), indent=1)
print("frames: %d in the sequence, %d captured, %d processed, %d dropped in the queue, %d tracked" %
      (frames, stats["captured"], stats["processed"], stats["dropped_queue"], stats["tracked"]))
print("poses: %d published, %d received by agvslam-echo, all in order and none missing: %s; delivered rate %.2f Hz" %
      (len(tracked), len(echo), summary["every_tracked_pose_received_in_order"], rate))
for name, key in [("capture -> outputs", "latency_capture_to_outputs_ms"), ("capture -> echo", "latency_capture_to_receive_ms")]:
    v = summary[key]
    print("latency %-18s median %6.1f ms  p99 %6.1f ms  max %6.1f ms" % (name, v["median"], v["p99"], v["max"]))
print("stages (median / p99 ms): " + ", ".join("%s %.1f / %.1f" % (k, v["median"], v["p99"]) for k, v in stage.items()))
print("load average before / after: %s / %s%s" % (load_before, load_after, ", agvslamd under SCHED_FIFO" if rt else ""))
EOF
record_finish "daemon_latency $scenario rt $rt" "agvslamd on the host: delivered rate and latency ($scenario, $frames frames, SCHED_FIFO $rt)"
