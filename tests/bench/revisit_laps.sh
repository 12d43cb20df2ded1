#!/usr/bin/env bash
# Map growth when the AGV drives the same loop again (memory stays bounded on long runs over the same area):
#   tests/bench/revisit_laps.sh [--build DIR] [--data DIR] [--seeds "101 102"] [--scenario scene4] [--laps 4]
#                               [--threads N] [--record]
# Generates <scenario>_<seed> under --data once (agvslam-sim), plays it --laps times in a row with loop closing
# (agvslam-run --repeat, --dynamic gt, --mapping inline) with the keyframe revisit rule of params/slam.yaml and
# with it turned off (tracking.keyframe_revisit_distance_m: 0, ORB-SLAM2's keyframe decision alone), and prints
# per run: keyframes and map points in the map after each lap, the map's memory, and the ATE RMSE over all laps.
set -euo pipefail
source "$(dirname "$0")/record.sh"
record_init "$0" "$@"
build=build/release
data=${TMPDIR:-/tmp}/agvslam-revisit-laps
seeds="101 102"
scenario=scene4
laps=4
threads=$(nproc)
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --data) data=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --scenario) scenario=$2; shift 2 ;;
    --laps) laps=$2; shift 2 ;;
    --record) record=1; shift ;;
    --threads) threads=$2; shift 2 ;;
    *) echo "revisit_laps.sh: unknown option '$1' (expected --build, --data, --seeds, --scenario, --laps, --threads, --record)" >&2; exit 2 ;;
  esac
done
sim=$build/bin/agvslam-sim
run=$build/bin/agvslam-run
for tool in "$sim" "$run"; do
  [[ -x $tool ]] || { echo "revisit_laps.sh: $tool not found; build first (cmake --build --preset release)" >&2; exit 2; }
done
here=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$data/revisit"
off_params=$data/revisit/slam_revisit_off.yaml
sed -E 's/^( *keyframe_revisit_distance_m:) *[0-9.]+/\1 0.0/' "$here/params/slam.yaml" > "$off_params"
grep -q "keyframe_revisit_distance_m: 0.0" "$off_params" || { echo "revisit_laps.sh: could not turn the rule off in $off_params" >&2; exit 1; }
record_start
printf "%-12s %-4s %-28s %-28s %9s %9s\n" sequence rule "keyframes after each lap" "map points after each lap" "memory MB" "ATE m"
for seed in $seeds; do
  seq=$data/${scenario}_$seed
  [[ -f $seq/objects.txt ]] || "$sim" --scenario "$scenario" --seed "$seed" --out "$seq" --threads "$threads" > "$seq.log" 2>&1
  for rule in on off; do
    out=$data/revisit/${scenario}_${seed}_$rule
    extra=()
    [[ $rule == off ]] && extra=(--params-slam "$off_params")
    "$run" --dataset "$seq" --out "$out.tum" --dynamic gt --mapping inline --loop on --repeat "$laps" \
      --json "$out.json" "${extra[@]}" > "$out.txt" 2> "$out.log" || { echo "revisit_laps.sh: agvslam-run failed, see $out.log" >&2; exit 1; }
    /usr/bin/env python3 - "$out.json" "${scenario}_$seed" "$rule" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
kf = "/".join(str(k) for k in j["laps"]["keyframes"])
mp = "/".join(str(k) for k in j["laps"]["map_points"])
ate = j.get("ate", {}).get("rmse_m", float("nan"))
print(f"{sys.argv[2]:<12} {sys.argv[3]:<4} {kf:<28} {mp:<28} {j['map']['memory_bytes'] / 1e6:9.1f} {ate:9.4f}")
PY
  done
done
record_finish "revisit_laps $scenario seeds $seeds" "Map growth over repeated laps ($scenario, $laps laps; seeds $seeds)"
