#!/usr/bin/env bash
# Runs the SLAM on simulator scenarios in the three --dynamic modes and tabulates the ATE:
#   tests/bench/slam_scenarios.sh [--build DIR] [--data DIR] [--seeds "101 102 103 104 105"]
#                                 [--scenarios "static scene1 scene2 scene3 scene4 scene5 scene6"]
#                                 [--modes "detector gt off"] [--mapping inline|thread] [--threads N]
#                                 [--semantic MODEL] [--generate-only] [--table-only] [--record]
# Generates each <scenario>_<seed> sequence under --data once (agvslam-sim, full default length; ~0.2-0.35 s per
# frame and core), runs agvslam-run on it per mode (trajectory, JSON and log under <data>/slam/), and prints one
# table (tests/bench/slam_table.py): per sequence the ATE RMSE per mode (SE(3)-aligned), drift (largest distance
# from the first position: the figure for scene1, where the AGV stands still), lost frames and the share of the pose
# inliers on ground-truth moving objects (agvslam-run MOVING_INLIERS: what masking can take away); per scenario the
# mean and standard deviation over the seeds, and the product's masking targets checked on the means.
# --mapping inline (default) maps each keyframe before the next frame: the same input gives the same result.
# --table-only prints the table from the results already under <data>/slam/.
# Mode `semantic` is the detector with the semantic keyframes (agvslam-run --dynamic detector --semantic MODEL;
# MODEL from --semantic, default the shipped params/models/pspnet_mnv2.onnx).
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
semantic_model=$(dirname "$0")/../../params/models/pspnet_mnv2.onnx
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --data) data=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --scenarios) scenarios=$2; shift 2 ;;
    --modes) modes=$2; shift 2 ;;
    --mapping) mapping=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --semantic) semantic_model=$2; shift 2 ;;
    --record) record=1; shift ;;
    --generate-only) generate_only=1; shift ;;
    --table-only) table_only=1; shift ;;
    *) echo "slam_scenarios.sh: unknown option '$1' (expected --build, --data, --seeds, --scenarios, --modes, --mapping, --threads, --semantic, --generate-only, --table-only, --record)" >&2; exit 2 ;;
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
      masking=(--dynamic "$mode")
      [[ $mode == semantic ]] && masking=(--dynamic detector --semantic "$semantic_model")
      "$run" --dataset "$seq" --out "$out.tum" "${masking[@]}" --mapping "$mapping" --json "$out.json" \
        > "$out.txt" 2> "$out.log" || echo "slam_scenarios.sh: agvslam-run failed on $seq ($mode), see $out.log" >&2
    done
  done
done
[[ $generate_only == 1 ]] && exit 0
record_start
/usr/bin/env python3 "$(dirname "$0")/slam_table.py" "$data/slam" "$modes" $scenarios -- $seeds
record_finish "slam_scenarios seeds $seeds mapping $mapping" "SLAM on the simulator scenes: ATE per --dynamic mode ($scenarios; seeds $seeds; mapping $mapping)"
