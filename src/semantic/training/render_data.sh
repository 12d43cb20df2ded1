#!/usr/bin/env bash
# Renders the semantic training or validation sequences with the simulator: one sequence per seed, the scenarios
# taken in turn so every scenario appears, each sequence its whole timeline squeezed into FRAMES frames (the
# segmenter learns from single frames, so many short sequences give more variety per rendered frame than a few
# long ones). The seeds must be ones no test or benchmark uses (tests: small seeds, 101-103, 9xxx).
#
#   render_data.sh SIM_BINARY SIM_PARAMS OUT_DIR FIRST_SEED LAST_SEED FRAMES
#   e.g. render_data.sh build/release/bin/agvslam-sim params/sim.yaml /work/semdata/train 5000 5099 10
#        render_data.sh build/release/bin/agvslam-sim params/sim.yaml /work/semdata/val 5100 5119 10
# A sequence whose folder already holds FRAMES class labels is kept, so an interrupted run resumes.
set -euo pipefail
if [ $# -ne 6 ]; then
  sed -n '2,10p' "$0"
  exit 2
fi
sim=$1 params=$2 out=$3 first=$4 last=$5 frames=$6
scenarios=(static scene1 scene2 scene3 scene4 scene5 scene6 follow crowd pallet oncoming)
mkdir -p "$out"
for ((seed = first; seed <= last; ++seed)); do
  scenario=${scenarios[$((seed % ${#scenarios[@]}))]}
  dir="$out/${scenario}_${seed}"
  if [ -d "$dir/class_0" ] && [ "$(ls "$dir/class_0" | wc -l)" -eq "$frames" ]; then continue; fi
  "$sim" --scenario "$scenario" --seed "$seed" --squeeze-to "$frames" --params "$params" --threads 2 --out "$dir" \
    >"$dir.log" 2>&1 || { cat "$dir.log"; exit 1; }
  echo "rendered $dir"
done
