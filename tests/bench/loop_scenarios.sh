#!/usr/bin/env bash
# Loop closing on simulator scenarios : ATE with --loop on and --loop off, loops detected, and
# whether every detected loop joins two places that really are the same (no false loop):
#   tests/bench/loop_scenarios.sh [--build DIR] [--data DIR] [--seeds "101 102 103 104 105"]
#                                 [--loop-scenarios "scene4 scene5"] [--line-scenarios "scene2 scene3"]
#                                 [--repeat N] [--dynamic gt|detector|off] [--mapping inline|thread]
#                                 [--threads N] [--generate-only] [--table-only] [--record]
# Generates each <scenario>_<seed> sequence under --data once (agvslam-sim, full default length; ~0.2 s per frame
# and core), runs agvslam-run on it with --loop on and --loop off (the loop scenarios played --repeat times in a row,
# default 2: one lap ends where it started, the second lap revisits the whole loop), and on the line scenarios with
# --loop on only (one pass: no place is seen twice, so any loop closed there is false). Results go to
# <data>/loop/<scenario>_<seed>_<on|off>.{tum,json,txt,log}.
# Table: ATE RMSE (SE(3)-aligned) per mode, reduction (1 - on/off, %), loops closed, the largest ground-truth
# distance between the two keyframes' cameras of a closed loop (a true loop joins views of the same place: well
# under 1 m here; "false" is flagged above 1.5 m), lost frames; then the per-scenario means over the seeds.
# --dynamic gt (default) masks the simulator's moving objects from the ground truth, so that the figures measure
# loop closing alone; --mapping inline (default) gives the same result for the same input.
set -euo pipefail
source "$(dirname "$0")/record.sh"
record_init "$0" "$@"
build=build/release
data=${TMPDIR:-/tmp}/agvslam-loop-scenarios
seeds="101 102 103 104 105"
loop_scenarios="scene4 scene5"
line_scenarios="scene2 scene3"
repeat=2
dynamic=gt
mapping=inline
threads=$(nproc)
generate_only=0
table_only=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --data) data=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --loop-scenarios) loop_scenarios=$2; shift 2 ;;
    --line-scenarios) line_scenarios=$2; shift 2 ;;
    --repeat) repeat=$2; shift 2 ;;
    --dynamic) dynamic=$2; shift 2 ;;
    --mapping) mapping=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --record) record=1; shift ;;
    --generate-only) generate_only=1; shift ;;
    --table-only) table_only=1; shift ;;
    *) echo "loop_scenarios.sh: unknown option '$1' (expected --build, --data, --seeds, --loop-scenarios, --line-scenarios, --repeat, --dynamic, --mapping, --threads, --generate-only, --table-only, --record)" >&2; exit 2 ;;
  esac
done
sim=$build/bin/agvslam-sim
run=$build/bin/agvslam-run
for tool in "$sim" "$run"; do
  [[ -x $tool ]] || { echo "loop_scenarios.sh: $tool not found; build first (cmake --build --preset release)" >&2; exit 2; }
done
mkdir -p "$data/loop"
generate() {
  local seq=$data/$1_$2
  if [[ ! -f $seq/objects.txt ]]; then
    "$sim" --scenario "$1" --seed "$2" --out "$seq" --threads "$threads" > "$seq.log" 2>&1
  fi
}
slam() {  # scenario seed loop repeat
  local out=$data/loop/$1_$2_$3
  "$run" --dataset "$data/$1_$2" --out "$out.tum" --dynamic "$dynamic" --mapping "$mapping" --loop "$3" \
    --repeat "$4" --json "$out.json" > "$out.txt" 2> "$out.log" ||
    echo "loop_scenarios.sh: agvslam-run failed on $data/$1_$2 (--loop $3), see $out.log" >&2
}
if [[ $table_only == 0 ]]; then
  for seed in $seeds; do
    for scenario in $loop_scenarios; do
      generate "$scenario" "$seed"
      [[ $generate_only == 1 ]] && continue
      slam "$scenario" "$seed" on "$repeat"
      slam "$scenario" "$seed" off "$repeat"
    done
    for scenario in $line_scenarios; do
      generate "$scenario" "$seed"
      [[ $generate_only == 1 ]] && continue
      slam "$scenario" "$seed" on 1
    done
  done
fi
[[ $generate_only == 1 ]] && exit 0
record_start
/usr/bin/python3 - "$data" "$loop_scenarios" "$line_scenarios" $seeds <<'PY'
import json, math, os, sys
data, loop_sc, line_sc, seeds = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4:]
def load(sc, seed, mode):
    p = f"{data}/loop/{sc}_{seed}_{mode}.json"
    return json.load(open(p)) if os.path.exists(p) else None
def gt_positions(sc, seed):
    p = f"{data}/{sc}_{seed}/poses.txt"
    if not os.path.exists(p):
        return None
    rows = [list(map(float, line.split())) for line in open(p) if line.strip()]
    return [(r[3], r[7], r[11]) for r in rows]
def loop_check(j, gt):
    """Loops closed and the largest ground-truth distance between the two keyframes' cameras (frame ids count
    the frames played, lap after lap)."""
    if not j:
        return 0, float("nan")
    loops = j.get("loops", [])
    worst = 0.0
    for e in loops:
        a, b = gt[e["frame"] % len(gt)], gt[e["loop_frame"] % len(gt)]
        worst = max(worst, math.dist(a, b))
    return len(loops), (worst if loops else float("nan"))
def mean(v):
    return sum(v) / len(v)
def ate(j):
    return j["ate"]["rmse_m"] if j and "ate" in j else float("nan")
print(f"{'sequence':<12}{'ATE on':>9}{'ATE off':>9}{'reduction':>10}{'loops':>6}{'loop gt dist':>13}{'lost on/off':>12}  verdict")
summary = {}
for sc in loop_sc:
    for seed in seeds:
        on, off, gt = load(sc, seed, "on"), load(sc, seed, "off"), gt_positions(sc, seed)
        if gt is None or not (on or off):
            continue
        a_on, a_off = ate(on), ate(off)
        red = (1 - a_on / a_off) * 100 if a_off > 0 else float("nan")
        n, dist = loop_check(on, gt)
        verdict = "FALSE LOOP" if n and dist > 1.5 else ("no loop" if n == 0 else ("ok" if red >= 50 else "reduction < 50 %"))
        lost = f"{on['frames']['lost'] if on else -1}/{off['frames']['lost'] if off else -1}"
        print(f"{sc + '_' + seed:<12}{a_on:>9.4f}{a_off:>9.4f}{red:>9.1f}%{n:>6}{dist:>13.3f}{lost:>12}  {verdict}")
        s = summary.setdefault(sc, {"on": [], "off": [], "red": [], "detected": 0, "runs": 0})
        s["on"].append(a_on); s["off"].append(a_off); s["red"].append(red)
        s["runs"] += 1; s["detected"] += 1 if n > 0 and not (dist > 1.5) else 0
for sc in line_sc:
    for seed in seeds:
        on, gt = load(sc, seed, "on"), gt_positions(sc, seed)
        if gt is None or not on:
            continue
        n, dist = loop_check(on, gt)
        verdict = "ok (no loop)" if n == 0 else "FALSE LOOP"
        print(f"{sc + '_' + seed:<12}{ate(on):>9.4f}{'-':>9}{'-':>10}{n:>6}{dist:>13.3f}{on['frames']['lost']:>12}  {verdict}")
        s = summary.setdefault(sc, {"false": 0, "runs": 0})
        s["runs"] += 1; s["false"] += 1 if n else 0
print("over seeds " + " ".join(seeds) + ":")
for sc, s in summary.items():
    if "on" in s:
        print(f"  {sc:<8} mean ATE on {mean(s['on']):.4f} off {mean(s['off']):.4f} (mean reduction "
              f"{mean(s['red']):.1f} %, min {min(s['red']):.1f} %), loop detected in {s['detected']}/{s['runs']} runs")
    else:
        print(f"  {sc:<8} false loops in {s['false']}/{s['runs']} runs")
PY
record_finish "loop_scenarios seeds $seeds" "Loop closing on the simulator scenes ($loop_scenarios x $repeat laps, $line_scenarios; seeds $seeds)"
