#!/usr/bin/env bash
# Renders the simulator sequences the shipped vocabulary is trained on (see README.md in this folder):
# every scenario (static, scene1..scene5) for every seed in SEEDS (default 900..960; the seed is also the layout and
# texture seed), FRAMES frames each (the whole scenario timeline played over FRAMES frames). None of these seeds
# is used by an evaluation, test or benchmark (those use seeds below 200).
#   usage: generate_training_images.sh SIM_BINARY OUT_DIR [FRAMES=12] [FIRST_SEED=900] [LAST_SEED=960]
set -euo pipefail
sim=${1:?path of agvslam-sim}
out=${2:?output folder}
frames=${3:-12}
first=${4:-900}
last=${5:-960}
mkdir -p "$out"
for seed in $(seq "$first" "$last"); do
  for scenario in static scene1 scene2 scene3 scene4 scene5; do
    dir="$out/${scenario}_s${seed}"
    if [[ -f "$dir/scenario.json" && -f "$dir/poses.txt" ]]; then continue; fi
    "$sim" --scenario "$scenario" --seed "$seed" --squeeze-to "$frames" --threads 1 --out "$dir" 2>/dev/null
    echo "$dir" >&2
  done
done
