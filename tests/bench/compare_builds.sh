#!/usr/bin/env bash
# Compares the outputs of two builds of agvslam on the same inputs, for changes that must not change behaviour
# (a refactor): simulator images and ground truth, detector masks and scores, SLAM trajectories.
#   tests/bench/compare_builds.sh --ref BUILD_DIR --new BUILD_DIR [--data DIR] [--out DIR] [--seeds "101 102 103"]
#       [--scenarios "scene1 scene2 scene3 scene4 scene5 scene6"] [--what "sim masks slam"] [--shared DIR]
#       [--params-dynamic FILE | --params-dynamic-ref FILE --params-dynamic-new FILE]
#   sim    renders every scenario's whole timeline over 40 frames with both builds' agvslam-sim and compares every
#          file (md5)
#   masks  runs both builds' agvslam-dynamic on <data>/<scenario>_<seed> (rendered once by the ref build, full
#          length) and compares every mask PNG (md5) and the JSON scores with the timings left out
#   slam   runs both builds' agvslam-run --mapping inline --dynamic detector|off on the shared KITTI 06, KITTI 01 and
#          EuRoC V1_01 excerpts and compares the trajectories (largest position difference, m)
# Sequences are rendered into --data once and reused; every output goes under --out (default: --data), so several
# comparisons can share one --data. Prints one line per comparison ("same" or what differs) and exits 1 when anything differs.
set -euo pipefail
ref=""
new=""
data=${TMPDIR:-/tmp}/agvslam-compare
out_root=""
seeds="101 102 103"
scenarios="scene1 scene2 scene3 scene4 scene5 scene6"
what="sim masks slam"
shared=${AGVSLAM_SHARED_DIR:-$(cd "$(dirname "$0")/../.." && pwd)/../shared}
params_ref=()
params_new=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --ref) ref=$2; shift 2 ;;
    --new) new=$2; shift 2 ;;
    --data) data=$2; shift 2 ;;
    --out) out_root=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --scenarios) scenarios=$2; shift 2 ;;
    --what) what=$2; shift 2 ;;
    --shared) shared=$2; shift 2 ;;
    --params-dynamic) params_ref=(--params-dynamic "$2"); params_new=(--params-dynamic "$2"); shift 2 ;;
    # a file whose layout changed between the builds: each build reads its own
    --params-dynamic-ref) params_ref=(--params-dynamic "$2"); shift 2 ;;
    --params-dynamic-new) params_new=(--params-dynamic "$2"); shift 2 ;;
    *) echo "compare_builds.sh: unknown option '$1' (expected --ref, --new, --data, --out, --seeds, --scenarios, --what, --shared, --params-dynamic, --params-dynamic-ref, --params-dynamic-new)" >&2; exit 2 ;;
  esac
done
[[ -n $ref && -n $new ]] || { echo "compare_builds.sh: --ref BUILD_DIR and --new BUILD_DIR are required" >&2; exit 2; }
for b in "$ref" "$new"; do
  for tool in agvslam-sim agvslam-dynamic agvslam-run; do
    [[ -x $b/bin/$tool ]] || { echo "compare_builds.sh: $b/bin/$tool not found; build that tree first" >&2; exit 2; }
  done
done
out_root=${out_root:-$data}
mkdir -p "$data" "$out_root"
differ=0
report() {  # name, status
  printf '%-44s %s\n' "$1" "$2"
  [[ $2 == same* ]] || differ=1
}

tree_md5() { (cd "$1" && find . -type f ! -name '*.log' -print0 | sort -z | xargs -0 md5sum); }

if [[ " $what " == *" sim "* ]]; then
  for scenario in static $scenarios; do
    for b in ref new; do
      dir=$out_root/sim_$b/$scenario
      rm -rf "$dir"; mkdir -p "$(dirname "$dir")"
      bin=$ref; [[ $b == new ]] && bin=$new
      # The whole timeline over 40 frames: --squeeze-to where the build has it, else --frames (which meant that).
      squeeze=--frames
      "$bin/bin/agvslam-sim" --help 2>/dev/null | grep -q -- --squeeze-to && squeeze=--squeeze-to
      "$bin/bin/agvslam-sim" --scenario "$scenario" --seed 101 "$squeeze" 40 --out "$dir" > "$dir.log" 2>&1
    done
    if diff <(tree_md5 "$out_root/sim_ref/$scenario") <(tree_md5 "$out_root/sim_new/$scenario") > "$out_root/sim_$scenario.diff"; then
      report "sim $scenario (40 frames)" "same ($(tree_md5 "$out_root/sim_ref/$scenario" | wc -l) files)"
    else
      report "sim $scenario (40 frames)" "DIFFERS: $(grep -c '^<' "$out_root/sim_$scenario.diff") files (see $out_root/sim_$scenario.diff)"
    fi
  done
fi

strip_timings() {  # JSON without timing fields (they differ from run to run)
  /usr/bin/env python3 - "$1" <<'PY'
import json, sys
def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if not (k == "ms" or k.endswith("_ms") or k in ("timings", "wall_s", "fps"))}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x
print(json.dumps(strip(json.load(open(sys.argv[1]))), sort_keys=True, indent=1))
PY
}

if [[ " $what " == *" masks "* ]]; then
  for scenario in $scenarios; do
    for seed in $seeds; do
      seq=$data/${scenario}_$seed
      if [[ ! -f $seq/objects.txt ]]; then
        "$ref/bin/agvslam-sim" --scenario "$scenario" --seed "$seed" --out "$seq" > "$seq.log" 2>&1
      fi
      for b in ref new; do
        bin=$ref; params=("${params_ref[@]}")
        [[ $b == new ]] && { bin=$new; params=("${params_new[@]}"); }
        out=$out_root/masks_$b/${scenario}_$seed
        rm -rf "$out"; mkdir -p "$(dirname "$out")"
        "$bin/bin/agvslam-dynamic" --dataset "$seq" "${params[@]}" --out "$out" --overlay-every 0 \
          --json "$out.json" > "$out.txt" 2>&1
      done
      a=$out_root/masks_ref/${scenario}_$seed
      n=$out_root/masks_new/${scenario}_$seed
      if ! diff <(cd "$a/mask" && md5sum ./*.png) <(cd "$n/mask" && md5sum ./*.png) > "$n.mask.diff"; then
        report "masks ${scenario}_$seed" "DIFFERS: $(grep -c '^<' "$n.mask.diff") masks (see $n.mask.diff)"
      elif ! diff <(strip_timings "$a.json") <(strip_timings "$n.json") > "$n.json.diff"; then
        report "masks ${scenario}_$seed" "masks same, JSON DIFFERS (see $n.json.diff)"
      else
        report "masks ${scenario}_$seed" "same ($(ls "$a/mask" | wc -l) masks, scores)"
      fi
    done
  done
fi

if [[ " $what " == *" slam "* ]]; then
  datasets=()
  for d in kitti06_f000-050 kitti01_f000-050 euroc_v101_f000-094; do
    if [[ -d $shared/data/$d ]]; then datasets+=("$d"); else echo "compare_builds.sh: $shared/data/$d missing; skipped" >&2; fi
  done
  for d in "${datasets[@]}"; do
    features=()
    [[ $d == kitti* ]] && features=(--params-features "$(dirname "$0")/../../params/features_kitti.yaml")
    for mode in detector off; do
      for b in ref new; do
        bin=$ref; [[ $b == new ]] && bin=$new
        out=$out_root/slam_$b/${d}_$mode
        mkdir -p "$(dirname "$out")"
        "$bin/bin/agvslam-run" --dataset "$shared/data/$d" "${features[@]}" --dynamic "$mode" --mapping inline \
          --out "$out.txt" > "$out.log" 2>&1 || true
      done
      a=$out_root/slam_ref/${d}_$mode.txt
      n=$out_root/slam_new/${d}_$mode.txt
      if [[ ! -s $a || ! -s $n ]]; then
        report "slam $d $mode" "DIFFERS: a trajectory is missing (see $out_root/slam_*/${d}_$mode.log)"
        continue
      fi
      r=$(/usr/bin/env python3 - "$a" "$n" <<'PY'
import sys
def load(p):
    rows = [l.split() for l in open(p) if l.strip() and not l.startswith("#")]
    return {r[0]: tuple(float(v) for v in r[1:4]) for r in rows}
a, n = load(sys.argv[1]), load(sys.argv[2])
if a.keys() != n.keys():
    print(f"frames {len(a)} vs {len(n)}"); sys.exit()
d = max((sum((x - y) ** 2 for x, y in zip(a[k], n[k])) ** 0.5 for k in a), default=0.0)
print(f"{len(a)} poses, max position difference {d:.3g} m")
PY
)
      if cmp -s "$a" "$n"; then report "slam $d $mode" "same (identical file, $r)"; else report "slam $d $mode" "DIFFERS: $r"; fi
    done
  done
fi
exit $differ
