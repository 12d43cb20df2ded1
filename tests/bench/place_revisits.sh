#!/usr/bin/env bash
# Place-recognition precision/recall of vocabularies on simulator revisits (seeds not used for training: the
# shipped vocabulary is trained on seeds 900-960, see params/vocabulary/README.md).
#
#   tests/bench/place_revisits.sh [--build DIR] [--cache DIR] [--vocabulary F[,F...]] [--frame-step N] [--json FILE]
#                                 [--record]
#
# Renders (once, cached) with agvslam-sim, each scenario's whole timeline over 350 frames (the loop: 28.7 m in
# 17.5 s, ~1.6 m/s, 8 cm between frames) or 200 frames (the aisle):
#   loop_scene4_s41   scene4 (the 6.4 m x 8.8 m loop, one person crosses), seed 41, back to its start
#   loop_static_s42   static (the same loop, nobody), seed 42
#   map_static_s43    static, seed 43: the map run of the relocalisation pair
#   query_scene5_s44  scene5 (three people) in the warehouse of seed 43 (--layout-seed 43), starting 7 m further on
#   line_scene2_s45   scene2 (13.6 m straight aisle, no revisit): every accepted answer is a false loop
# then runs agvslam-vocab --evaluate: loop revisits in each loop sequence (frames >= 10 s older), relocalisation
# of the query run against the map run (camera within 1 m and 20 degrees), and false loops on the aisle.
set -euo pipefail
source "$(dirname "$0")/record.sh"
record_init "$0" "$@"
root=$(cd "$(dirname "$0")/../.." && pwd)
build="$root/build/release"
cache=""
vocabulary="$root/params/vocabulary/agvslam_orb_k10l5.bin"
frame_step=1
json=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    --vocabulary) vocabulary=$2; shift 2 ;;
    --frame-step) frame_step=$2; shift 2 ;;
    --record) record=1; shift ;;
    --json) json=$2; shift 2 ;;
    *) echo "unknown option $1 (expected --build, --cache, --vocabulary, --frame-step, --json, --record)" >&2; exit 2 ;;
  esac
done
cache=${cache:-$build/place_revisits}
sim="$build/bin/agvslam-sim"
vocab="$build/bin/agvslam-vocab"
for tool in "$sim" "$vocab"; do
  [[ -x $tool ]] || { echo "$tool not built (cmake --build $build --target agvslam-sim agvslam-vocab)" >&2; exit 2; }
done
mkdir -p "$cache"
render() {  # name, agvslam-sim arguments...
  local dir="$cache/$1"; shift
  if [[ ! -f "$dir/scenario.json" ]]; then
    echo "rendering $dir" >&2
    "$sim" "$@" --threads 2 --out "$dir.tmp" >&2 && rm -rf "$dir" && mv "$dir.tmp" "$dir"
  fi
}
render loop_scene4_s41 --scenario scene4 --seed 41 --squeeze-to 350
render loop_static_s42 --scenario static --seed 42 --squeeze-to 350
render map_static_s43 --scenario static --seed 43 --squeeze-to 350
render query_scene5_s44 --scenario scene5 --seed 44 --layout-seed 43 --start-offset 7 --squeeze-to 350
render line_scene2_s45 --scenario scene2 --seed 45 --squeeze-to 200
record_start
args=(--evaluate --vocabulary "$vocabulary" --frame-step "$frame_step" --threads 2)
cd "$root"
# Loops (the lap takes 17.5 s: frames >= 10 s older) and relocalisation.
"$vocab" "${args[@]}" --loop "$cache/loop_scene4_s41,$cache/loop_static_s42" \
  --map "$cache/map_static_s43" --query "$cache/query_scene5_s44" ${json:+--json "$json"}
# The aisle has no revisit (10 s long: frames >= 3 s, i.e. >= 5 m, older): every answer is false; max_false is
# the score a loop threshold must stay above.
"$vocab" "${args[@]}" --loop "$cache/line_scene2_s45" --min-gap-s 3 ${json:+--json "${json%.json}_aisle.json"}
record_finish "place_revisits" "Place recognition on simulator revisits (shipped vocabulary unless --vocabulary)"
