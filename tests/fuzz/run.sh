#!/usr/bin/env bash
# Runs fuzz targets for a set time each and prints the executions of each.
#   tests/fuzz/run.sh [--build DIR] [--time SECONDS] [--jobs N] [TARGET...]
# DIR: the fuzz build (default build/fuzz: cmake --preset fuzz && cmake --build --preset fuzz --target fuzz_targets,
# or tests/fuzz/build.sh); SECONDS: per target (default 60); N: targets run at once (default 1); TARGETs: default
# all (tests/fuzz/targets/*.cpp). Each run starts from the checked-in seeds (corpus/TARGET) and the kept crash
# inputs (regressions/TARGET); inputs that add coverage go to DIR/corpus/TARGET (kept between runs), a crash to
# DIR/artifacts/TARGET/ (keep it under regressions/TARGET once fixed). Exit status 1 when any target crashed.
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="$here/../../build/fuzz"
seconds=60
jobs=1
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --time) seconds="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    -h|--help) sed -n 2,9p "$0"; exit 0 ;;
    *) targets+=("$1"); shift ;;
  esac
done
if [ ${#targets[@]} -eq 0 ]; then
  for f in "$here"/targets/*.cpp; do targets+=("$(basename "$f" .cpp)"); done
fi

run_one() {
  local t="$1" exe="$build/tests/fuzz/fuzz_$1"
  if [ ! -x "$exe" ]; then echo "fuzz $t: $exe not built (tests/fuzz/build.sh)" >&2; return 1; fi
  mkdir -p "$build/corpus/$t" "$build/artifacts/$t" "$build/logs"
  local inputs=("$here/corpus/$t")
  [ -d "$here/regressions/$t" ] && inputs+=("$here/regressions/$t")
  # -timeout: one input over 10 s is a hang; -rss_limit_mb / -malloc_limit_mb: an allocation the input sizes
  # without bound is a finding too.
  "$exe" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 \
    -artifact_prefix="$build/artifacts/$t/" "$build/corpus/$t" "${inputs[@]}" > "$build/logs/$t.log" 2>&1
  local rc=$?
  local execs
  execs=$(grep -a -m1 'stat::number_of_executed_units' "$build/logs/$t.log" | awk '{print $2}')
  local corpus
  corpus=$(ls "$build/corpus/$t" | wc -l)
  if [ $rc -ne 0 ]; then
    printf '%-14s CRASH (exit %d) after %s executions: %s\n' "$t" "$rc" "${execs:-?}" "$build/logs/$t.log"
    grep -a -m3 -E 'ERROR: |runtime error|uncaught exception|Test unit written' "$build/logs/$t.log" | sed 's/^/    /'
    return 1
  fi
  printf '%-14s %10s executions in %ss (%s/s), corpus %s\n' "$t" "$execs" "$seconds" "$((execs / seconds))" "$corpus"
}

# Targets that take a path write each input to a file in $TMPDIR: on a disk that costs ~5 ms an input, in tmpfs
# ~0.1 ms.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi

export -f run_one
export build here seconds
status=0
if [ "$jobs" -le 1 ]; then
  for t in "${targets[@]}"; do run_one "$t" || status=1; done
else
  printf '%s\n' "${targets[@]}" | xargs -P "$jobs" -I{} bash -c 'run_one "$@"' _ {} || status=1
fi
exit $status
