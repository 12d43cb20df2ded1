#!/usr/bin/env bash
# Long run of agvslamd: a simulator loop with people (scene5: the AGV drives a 6.4 m x 8.8 m loop back to its
# start while a person walks ahead of it) played again and again by the dataset source, as fast as the pipeline
# takes frames, until FRAMES poses went out; then SIGTERM (the map is saved on stop). Pipeline as on a vehicle:
# detector, tracking, local mapping in its thread, loop closing, DDS on loopback in a private network namespace.
#
#   tests/bench/soak.sh [--build DIR] [--data SEQ] [--scenario scene5] [--seed 31] [--frames 20000]
#                       [--sample-s 10] [--out DIR] [--record]
#
# Every SAMPLE seconds it reads the daemon's resident memory, threads and open file descriptors (/proc) and its
# status line (keyframes, map points, dropped frames). Reports: RSS at start (after the first pass), middle and end,
# and its growth over the second half per 1000 frames; threads and descriptors (min / max after start-up); map size
# per pass; frames lost; ATE per pass of the loop against the ground truth, all under the one SE(3) alignment of
# the first pass (so the last pass is scored in the frame the first one set); the stop time and the saved map.
# --data: a sequence written by agvslam-sim (default: rendered once into BUILD/bench-data). Needs `unshare -n`.
set -euo pipefail
source "$(dirname "$0")/record.sh"
record_init "$0" "$@"
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/../.." && pwd)
build=$src/build/release
data=""
scenario=scene5
seed=31
frames=20000
sample_s=10
out=""
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$(cd "$2" && pwd); shift 2 ;;
    --data) data=$(cd "$2" && pwd); shift 2 ;;
    --scenario) scenario=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --sample-s) sample_s=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --record) record=1; shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) echo "soak.sh: unknown option '$1' (expected --build, --data, --scenario, --seed, --frames, --sample-s, --out, --record)" >&2; exit 2 ;;
  esac
done
bin=$build/bin
for t in agvslamd agvslam-sim; do
  [ -x "$bin/$t" ] || { echo "soak.sh: $bin/$t not built (cmake --build --preset release)" >&2; exit 2; }
done
out=${out:-$(mktemp -d /tmp/agvslamd-soak.XXXXXX)}
mkdir -p "$out"
out=$(cd "$out" && pwd)
if [ -z "$data" ]; then
  data=$build/bench-data/${scenario}_s${seed}
  if [ ! -f "$data/.complete" ]; then
    echo "soak.sh: rendering $scenario seed $seed -> $data"
    rm -rf "$data"
    "$bin/agvslam-sim" --scenario "$scenario" --seed "$seed" --threads "$(nproc)" --out "$data" >/dev/null
    touch "$data/.complete"
  fi
fi
[ -f "$data/poses.txt" ] || { echo "soak.sh: $data/poses.txt missing (expected an agvslam-sim sequence)" >&2; exit 2; }
ns="unshare -n"
unshare -n true 2>/dev/null || ns="unshare -rn"

cat >"$out/agvslamd.yaml" <<EOF
source:
  type: dataset
  dataset: $data
  rate: 0
  loop: true
stages:
  features: $src/params/features.yaml
  slam: $src/params/slam.yaml
  dynamic: $src/params/dynamic.yaml
  stereo: $src/params/stereo.yaml
  place: $src/params/place.yaml
pipeline:
  dynamic: detector
  mapping: thread
base_link:
  z_m: 0.5
map:
  file: $out/soak.map
  mode: map
  save_on_stop: true
dds:
  network_interface: lo
  topic_namespace: agvslam_soak
log:
  pose_log: $out/poses.jsonl
  stats_every_s: $sample_s
EOF

cat >"$out/run.sh" <<EOF
ip link set lo up
$bin/agvslamd --config $out/agvslamd.yaml --json $out/stats.json > $out/daemon.out 2> $out/daemon.err &
pid=\$!
start=\$(date +%s.%N)
echo "t_s rss_kb threads fds poses" > $out/samples.txt
while kill -0 \$pid 2>/dev/null; do
  sleep $sample_s
  [ -r /proc/\$pid/status ] || break
  rss=\$(awk '/^VmRSS:/ {print \$2}' /proc/\$pid/status)
  threads=\$(ls /proc/\$pid/task | wc -l)
  fds=\$(ls /proc/\$pid/fd | wc -l)
  poses=\$(grep -c '"heartbeat":false' $out/poses.jsonl || true)
  echo "\$(awk "BEGIN {print \$(date +%s.%N) - \$start}") \$rss \$threads \$fds \$poses" >> $out/samples.txt
  if [ "\$poses" -ge $frames ]; then
    t0=\$(date +%s.%N)
    kill -TERM \$pid
    wait \$pid
    rc=\$?
    echo "stop_s \$(awk "BEGIN {print \$(date +%s.%N) - \$t0}") rc \$rc" > $out/stop.txt
    exit \$rc
  fi
done
wait \$pid
echo "soak.sh: agvslamd ended before $frames poses (exit \$?)" >&2
exit 1
EOF
echo "soak.sh: $scenario sequence $data looped for $frames frames; logs in $out"
$ns sh "$out/run.sh"

record_start
/usr/bin/python3 - "$out" "$data" "$frames" <<'EOF'
import json, re, sys
import numpy as np

out, data, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
gt = np.loadtxt(data + "/poses.txt").reshape(-1, 3, 4)
n_seq = len(gt)
log = [json.loads(l) for l in open(out + "/poses.jsonl") if '"heartbeat":false' in l]
samples = np.loadtxt(out + "/samples.txt", skiprows=1, ndmin=2)
stop = open(out + "/stop.txt").read().split()
stats = json.load(open(out + "/stats.json"))

# Passes through the loop: a new pass begins where the dataset index goes back.
passes, cur, last = [], [], -1
for l in log:
    k = l["source_index"]
    if k < last and cur:
        passes.append(cur)
        cur = []
    cur.append(l)
    last = k
if cur:
    passes.append(cur)

def umeyama(src, dst):
    mu_s, mu_d = src.mean(0), dst.mean(0)
    u, _, vt = np.linalg.svd((dst - mu_d).T @ (src - mu_s))
    d = np.diag([1, 1, np.sign(np.linalg.det(u @ vt))])
    R = u @ d @ vt
    return R, mu_d - R @ mu_s

def tracked(p, map_id):
    return [l for l in p if l["sample"]["tracking_state"] == 1 and l["sample"]["map_id"] == map_id]

first_map = log[0]["sample"]["map_id"]
ref = tracked(passes[0], first_map)
est = np.array([l["sample"]["t"] for l in ref])
# Ground truth: the left camera in the first camera's frame; base_link sits a fixed 0.5 m below it, which the
# alignment's translation takes up on level ground.
truth = np.array([gt[l["source_index"]][:, 3] for l in ref])
R, t = umeyama(est, truth)

print("agvslamd soak: %d frames (%d passes of the %d-frame %s), detector, mapping thread, loop closing" %
      (len(log), len(passes), n_seq, data.rstrip("/").split("/")[-1]))
print("%6s %8s %8s %9s %8s %10s" % ("pass", "frames", "tracked", "other map", "lost", "ATE m"))
rows = []
for i, p in enumerate(passes):
    tr = tracked(p, first_map)
    other = sum(1 for l in p if l["sample"]["map_id"] != first_map)
    lost = sum(1 for l in p if l["sample"]["tracking_state"] == 3)
    if tr:
        e = (R @ np.array([l["sample"]["t"] for l in tr]).T).T + t
        g = np.array([gt[l["source_index"]][:, 3] for l in tr])
        ate = float(np.sqrt(np.mean(np.sum((e - g) ** 2, 1))))
    else:
        ate = float("nan")
    rows.append((i + 1, len(p), len(tr), other, lost, ate))
shown = rows if len(rows) <= 12 else rows[:4] + [None] + rows[len(rows) // 2 - 1:len(rows) // 2 + 1] + [None] + rows[-4:]
for r in shown:
    print("   ..." if r is None else "%6d %8d %8d %9d %8d %10.4f" % r)
full = [r for r in rows if r[1] >= 0.9 * n_seq]
print("ATE first / middle / last full pass: %.4f / %.4f / %.4f m" %
      (full[0][5], full[len(full) // 2][5], full[-1][5]) if full else "no full pass")

# Memory, threads, descriptors: start = the first sample after the first pass.
t_s, rss, thr, fds, poses = samples.T
after = poses >= n_seq
if after.any():
    i0 = int(np.argmax(after))
    mid = i0 + (len(rss) - 1 - i0) // 2
    half = samples[mid:]
    slope = np.polyfit(half[:, 4], half[:, 1] / 1024.0, 1)[0] * 1000 if len(half) >= 3 else float("nan")
    print("RSS MB at start (frame %d) / middle (frame %d) / end (frame %d): %.1f / %.1f / %.1f; second half %+.2f MB per "
          "1000 frames" % (poses[i0], poses[mid], poses[-1], rss[i0] / 1024, rss[mid] / 1024, rss[-1] / 1024, slope))
    print("threads %d-%d, open descriptors %d-%d (after the first pass)" %
          (thr[i0:].min(), thr[i0:].max(), fds[i0:].min(), fds[i0:].max()))
status = [re.search(r"(\d+) frames .*?dropped (\d+).*?keyframes (\d+), map points (\d+)", l)
          for l in open(out + "/daemon.err") if "status:" in l]
status = [tuple(int(x) for x in m.groups()) for m in status if m]
if status:
    picks = [status[0], status[len(status) // 4], status[len(status) // 2], status[3 * len(status) // 4], status[-1]]
    print("map (frames: keyframes / map points): " +
          ", ".join("%d: %d / %d" % (s[0], s[2], s[3]) for s in picks))
print("rate %.1f frames/s over %.0f s; dropped %d; stop after SIGTERM %.2f s, exit %s; map saved: %s" %
      (len(log) / t_s[-1], t_s[-1], stats.get("dropped_queue", 0) + stats.get("dropped_source", 0), float(stop[1]),
       stop[3], "%d keyframes, %d map points" % (stats.get("keyframes", 0), stats.get("map_points", 0))))
EOF
ls -la "$out/soak.map" | awk '{print "map file: " $5 " bytes"}'
record_finish soak "agvslamd soak (looped simulator scene, daemon RSS / threads / descriptors / map / ATE per pass)"
