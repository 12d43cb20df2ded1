#!/usr/bin/env bash
# Runs the SLAM on simulator scenarios in the three --dynamic modes and tabulates the ATE:
#   tests/bench/slam_scenarios.sh [--build DIR] [--data DIR] [--seeds "101 102 103 104 105"]
#                                 [--scenarios "static scene1 scene2 scene3 scene4 scene5 scene6"]
#                                 [--modes "detector gt off"] [--mapping inline|thread] [--threads N]
#                                 [--generate-only] [--table-only] [--record]
# Generates each <scenario>_<seed> sequence under --data once (agvslam-sim, full default length; ~0.2-0.35 s per
# frame and core), runs agvslam-run on it per mode (trajectory, JSON and log under <data>/slam/), and prints one
# line per sequence: ATE RMSE per mode (SE(3)-aligned), drift (largest distance from the first position: the
# figure for scene1, where the AGV stands still), detector vs off (reduction, %), detector vs gt (%), lost frames,
# the median tracking-thread CPU time per frame (ms), and the share of the pose inliers that lay on ground-truth
# moving objects with --dynamic off and detector (agvslam-run MOVING_INLIERS: what masking can take away); then
# the per-scenario means over the seeds.
# --mapping inline (default) maps each keyframe before the next frame: the same input gives the same result.
# --table-only prints the table from the results already under <data>/slam/.
set -euo pipefail
source "$(dirname "$0")/record.sh"
record_init "$0" "$@"
build=build/release
data=${TMPDIR:-/tmp}/agvslam-slam-scenarios
seeds="101 102 103 104 105"
scenarios="static scene1 scene2 scene3 scene4 scene5 scene6"
modes="detector gt off"
mapping=inline
threads=$(nproc)
generate_only=0
table_only=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --data) data=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --scenarios) scenarios=$2; shift 2 ;;
    --modes) modes=$2; shift 2 ;;
    --mapping) mapping=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --record) record=1; shift ;;
    --generate-only) generate_only=1; shift ;;
    --table-only) table_only=1; shift ;;
    *) echo "slam_scenarios.sh: unknown option '$1' (expected --build, --data, --seeds, --scenarios, --modes, --mapping, --threads, --generate-only, --table-only, --record)" >&2; exit 2 ;;
  esac
done
sim=$build/bin/agvslam-sim
run=$build/bin/agvslam-run
for tool in "$sim" "$run"; do
  [[ -x $tool ]] || { echo "slam_scenarios.sh: $tool not found; build first (cmake --build --preset release)" >&2; exit 2; }
done
mkdir -p "$data/slam"
[[ $table_only == 1 ]] && scenarios_to_run="" || scenarios_to_run=$scenarios
for scenario in $scenarios_to_run; do
  for seed in $seeds; do
    seq=$data/${scenario}_$seed
    if [[ ! -f $seq/objects.txt ]]; then
      "$sim" --scenario "$scenario" --seed "$seed" --out "$seq" --threads "$threads" > "$seq.log" 2>&1
    fi
    [[ $generate_only == 1 ]] && continue
    for mode in $modes; do
      out=$data/slam/${scenario}_${seed}_$mode
      "$run" --dataset "$seq" --out "$out.tum" --dynamic "$mode" --mapping "$mapping" --json "$out.json" \
        > "$out.txt" 2> "$out.log" || echo "slam_scenarios.sh: agvslam-run failed on $seq ($mode), see $out.log" >&2
    done
  done
done
[[ $generate_only == 1 ]] && exit 0
record_start
/usr/bin/env python3 - "$data/slam" "$modes" $scenarios -- $seeds <<'PY'
import json, os, sys
root, modes = sys.argv[1], sys.argv[2].split()
args = sys.argv[3:]
sep = args.index("--")
scenarios, seeds = args[:sep], args[sep + 1:]
def load(sc, seed, mode):
    p = f"{root}/{sc}_{seed}_{mode}.json"
    return json.load(open(p)) if os.path.exists(p) else None
head = f"{'sequence':<14}" + "".join(f"{'ATE ' + m:>13}" for m in modes) + f"{'drift det':>11}{'det/off':>9}{'det/gt':>8}{'lost':>6}{'trk cpu':>8}{'mov off':>9}{'mov det':>9}"
print(head)
means = {}
for sc in scenarios:
    for seed in seeds:
        js = {m: load(sc, seed, m) for m in modes}
        ate = {m: (j["ate"]["rmse_m"] if j and "ate" in j else float("nan")) for m, j in js.items()}
        ref = js.get("detector") or next((j for j in js.values() if j), None)
        line = f"{sc + '_' + seed:<14}" + "".join(f"{ate[m]:>13.4f}" for m in modes)
        drift = ref["drift_m"] if ref else float("nan")
        red = (1 - ate["detector"] / ate["off"]) * 100 if "detector" in ate and "off" in ate and ate["off"] > 0 else float("nan")
        vs_gt = (ate["detector"] / ate["gt"] - 1) * 100 if "detector" in ate and "gt" in ate and ate["gt"] > 0 else float("nan")
        lost = sum(j["frames"]["lost"] for j in js.values() if j)
        t = ref["timings"] if ref else {}
        trk = t.get("tracking_cpu", t.get("tracking", {})).get("median_ms", float("nan")) if ref else float("nan")
        # Share of the pose inliers on ground-truth moving objects (agvslam-run MOVING_INLIERS): what masking can
        # take away from the pose.
        mov = {m: (100 * j["moving_inliers"]["fraction"] if j and "moving_inliers" in j else float("nan")) for m, j in js.items()}
        print(line + f"{drift:>11.4f}{red:>8.1f}%{vs_gt:>7.1f}%{lost:>6}{trk:>8.2f}{mov.get('off', float('nan')):>8.2f}%{mov.get('detector', float('nan')):>8.2f}%")
        for m in modes:
            means.setdefault((sc, m), []).append(ate[m])
            means.setdefault((sc, "mov " + m), []).append(mov[m])
        means.setdefault((sc, "drift"), []).append(drift)
print("mean over seeds " + " ".join(seeds) + ":")
for sc in scenarios:
    vals = {m: sum(means[(sc, m)]) / len(means[(sc, m)]) for m in modes}
    extra = ""
    if "detector" in vals and "off" in vals and vals["off"] > 0:
        extra += f"  detector vs off {(1 - vals['detector'] / vals['off']) * 100:+.1f}% lower"
    if "detector" in vals and "gt" in vals and vals["gt"] > 0:
        extra += f"  detector vs gt {(vals['detector'] / vals['gt'] - 1) * 100:+.1f}%"
    if "gt" in vals and "off" in vals and vals["off"] > 0:
        extra += f"  gt vs off {(1 - vals['gt'] / vals['off']) * 100:+.1f}% lower"
    d = means[(sc, "drift")]
    for m in ("off", "detector"):
        if m in modes:
            v = means[(sc, "mov " + m)]
            extra += f"  moving inliers {m} {sum(v) / len(v):.2f}%"
    print(f"  {sc:<8}" + "".join(f"  ATE {m} {vals[m]:.4f}" for m in modes) + f"  drift {sum(d) / len(d):.4f}" + extra)
PY
record_finish "slam_scenarios seeds $seeds mapping $mapping" "SLAM on the simulator scenes: ATE per --dynamic mode ($scenarios; seeds $seeds; mapping $mapping)"
