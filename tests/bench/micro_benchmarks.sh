#!/usr/bin/env bash
# Runs agvslam-bench (Google Benchmark, one case per stage) with repetitions and prints one line per case: the median
# over the repetitions of the time per iteration (wall and CPU) and the case's counters (per-stage means, p95 ...):
#   tests/bench/micro_benchmarks.sh [--build DIR] [--filter REGEX] [--repetitions N] [--record]
# Default filter: the cases that carry the product's speed targets (detector, ORB extraction, stereo matching,
# tracking, place recognition). --filter . runs every case.
set -euo pipefail
source "$(dirname "$0")/record.sh"
record_init "$0" "$@"
build=build/release
default_filter='BM_DynamicDetector(Static|ThreePeople)$|BM_FeaturesOrbExtract/|BM_FeaturesCvOrbReference|BM_FeaturesStereoMatch/|BM_SlamTrackStereoEuroc|BM_SlamLocalBa|BM_PlaceVocabularyLoad|BM_PlaceTransform|BM_SimStereoFrame'
filter=$default_filter
repetitions=5
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --filter) filter=$2; shift 2 ;;
    --repetitions) repetitions=$2; shift 2 ;;
    --record) record=1; shift ;;
    *) echo "micro_benchmarks.sh: unknown option '$1' (expected --build, --filter, --repetitions, --record)" >&2; exit 2 ;;
  esac
done
bench=$build/bin/agvslam-bench
[[ -x $bench ]] || { echo "micro_benchmarks.sh: $bench not found; build first (cmake --build --preset release --target agvslam-bench)" >&2; exit 2; }
json=$(mktemp)
"$bench" --benchmark_filter="$filter" --benchmark_repetitions="$repetitions" --benchmark_report_aggregates_only=true \
  --benchmark_out="$json" --benchmark_out_format=json > /dev/null
record_start
/usr/bin/env python3 - "$json" "$repetitions" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print(f"median of {sys.argv[2]} repetitions; times per iteration")
print(f"{'case':<44}{'wall ms':>10}{'cpu ms':>10}  counters")
for b in j["benchmarks"]:
    if b.get("aggregate_name") != "median":
        continue
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b.get("time_unit", "ns")]
    skip = {"name", "run_name", "run_type", "repetitions", "threads", "iterations", "real_time", "cpu_time",
            "time_unit", "aggregate_name", "aggregate_unit", "family_index", "per_family_instance_index",
            "repetition_index", "label"}
    counters = ", ".join(f"{k} {v:.3g}" for k, v in b.items() if k not in skip and isinstance(v, (int, float)))
    print(f"{b['run_name']:<44}{b['real_time'] * scale:>10.3f}{b['cpu_time'] * scale:>10.3f}  {counters}")
ctx = j.get("context", {})
print(f"host: {ctx.get('num_cpus', '?')} CPUs at {ctx.get('mhz_per_cpu', '?')} MHz, library build {ctx.get('library_build_type', '?')}")
PY
rm -f "$json"
if [[ $filter == "$default_filter" ]]; then
  record_finish "micro_benchmarks" "agvslam-bench: the stages that carry speed targets (Google Benchmark)"
else
  record_finish "micro_benchmarks $filter" "agvslam-bench: $filter (Google Benchmark)"
fi
