#!/usr/bin/env bash
# SLAM and the detector on the real excerpts in ../shared/data (KITTI 06: parked cars; KITTI 01: highway with moving
# cars; EuRoC V1_01: a camera nearly still):
#   tests/bench/real_data.sh [--build DIR] [--shared DIR] [--out DIR] [--modes "detector off"]
#                            [--mapping inline|thread] [--speed X] [--runs N] [--record]
# Per dataset and --dynamic mode, agvslam-run's ATE RMSE against the dataset's ground truth (SE(3)-aligned), the
# largest distance from the first position (drift; the figure for EuRoC, where the camera hardly moves), frames
# tracked / lost, and the tracking thread's median CPU time per frame, as mean and spread over --runs runs
# (--mapping inline gives the same result every run; thread, with --speed 1, runs as on a vehicle). Then the
# detector alone on each excerpt: dynamic regions per frame (agvslam-dynamic).
set -euo pipefail
source "$(dirname "$0")/record.sh"
record_init "$0" "$@"
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$root/build/release
shared=${AGVSLAM_SHARED_DIR:-$root/../shared}
out=${TMPDIR:-/tmp}/agvslam-real-data
modes="detector off"
mapping=inline
speed=0
runs=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --shared) shared=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --modes) modes=$2; shift 2 ;;
    --mapping) mapping=$2; shift 2 ;;
    --speed) speed=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --record) record=1; shift ;;
    *) echo "real_data.sh: unknown option '$1' (expected --build, --shared, --out, --modes, --mapping, --speed, --runs, --record)" >&2; exit 2 ;;
  esac
done
for tool in agvslam-run agvslam-dynamic; do
  [[ -x $build/bin/$tool ]] || { echo "real_data.sh: $build/bin/$tool not found; build first (cmake --build --preset release)" >&2; exit 2; }
done
datasets=()
for d in kitti06_f000-050 kitti01_f000-050 euroc_v101_f000-094; do
  if [[ -d $shared/data/$d ]]; then datasets+=("$d"); else echo "real_data.sh: $shared/data/$d not found (--shared DIR or AGVSLAM_SHARED_DIR)" >&2; exit 2; fi
done
mkdir -p "$out"
for d in "${datasets[@]}"; do
  features=()
  [[ $d == kitti* ]] && features=(--params-features "$root/params/features_kitti.yaml")
  for mode in $modes; do
    for ((r = 1; r <= runs; ++r)); do
      o=$out/${d}_${mode}_$r
      "$build/bin/agvslam-run" --dataset "$shared/data/$d" "${features[@]}" --dynamic "$mode" --mapping "$mapping" \
        --speed "$speed" --out "$o.tum" --json "$o.json" > "$o.txt" 2> "$o.log" ||
        echo "real_data.sh: agvslam-run failed on $d ($mode, run $r), see $o.log" >&2
    done
  done
  "$build/bin/agvslam-dynamic" --dataset "$shared/data/$d" --out "$out/${d}_dynamic" --overlay-every 10 \
    --json "$out/${d}_dynamic.json" > "$out/${d}_dynamic.txt" 2> "$out/${d}_dynamic.log" ||
    echo "real_data.sh: agvslam-dynamic failed on $d, see $out/${d}_dynamic.log" >&2
done
record_start
/usr/bin/env python3 - "$out" "$modes" "$runs" "$mapping" "$speed" "${datasets[@]}" <<'PY'
import json, math, os, sys
out, modes, runs, mapping, speed = sys.argv[1], sys.argv[2].split(), int(sys.argv[3]), sys.argv[4], sys.argv[5]
datasets = sys.argv[6:]
def mean_sd(v):
    v = [x for x in v if not math.isnan(x)]
    if not v:
        return float("nan"), float("nan")
    m = sum(v) / len(v)
    return m, (sum((x - m) ** 2 for x in v) / (len(v) - 1)) ** 0.5 if len(v) > 1 else 0.0
print(f"agvslam-run --mapping {mapping} --speed {speed}, {runs} run(s) each: mean (sd)")
print(f"{'dataset':<22}{'mode':<10}{'ATE RMSE m':>20}{'drift m':>18}{'tracked':>9}{'lost':>6}{'trk cpu ms':>12}")
for d in datasets:
    for mode in modes:
        js = []
        for r in range(1, runs + 1):
            p = f"{out}/{d}_{mode}_{r}.json"
            if os.path.exists(p):
                js.append(json.load(open(p)))
        if not js:
            print(f"{d:<22}{mode:<10}  no result (see {out}/{d}_{mode}_*.log)")
            continue
        # EuRoC's excerpt has ground truth for too few frames of its own time stamps: no ATE, drift only.
        ate = mean_sd([j.get("ate", {}).get("rmse_m", float("nan")) for j in js])
        drift = mean_sd([j.get("drift_m", float("nan")) for j in js])
        tracked = sum(j["frames"]["tracked"] for j in js) / len(js)
        lost = sum(j["frames"]["lost"] for j in js) / len(js)
        t = [j["timings"].get("tracking_cpu", j["timings"].get("tracking", {})).get("median_ms", float("nan")) for j in js]
        print(f"{d:<22}{mode:<10}{ate[0]:>11.4f} ({ate[1]:.4f}){drift[0]:>10.4f} ({drift[1]:.4f}){tracked:>9.0f}{lost:>6.0f}"
              f"{mean_sd(t)[0]:>12.2f}")
print("agvslam-dynamic (default settings): dynamic regions")
for d in datasets:
    p = f"{out}/{d}_dynamic.json"
    if not os.path.exists(p):
        print(f"  {d}: no result")
        continue
    j = json.load(open(p))
    n = j["frames"]["detected"]
    regions = j["regions"]["total"]
    print(f"  {d:<22}{regions} regions in {n} frames ({regions / max(1, n):.2f} per frame); overlays in {out}/{d}_dynamic/overlay")
PY
record_finish "real_data mapping $mapping speed $speed runs $runs" "SLAM and the detector on the real excerpts (mapping $mapping, speed $speed, $runs run(s))"
