#!/usr/bin/env bash
# DDS publish -> receive latency between two processes over loopback, in a private network namespace:
# agvslam-pose-replay stamps each sample with CLOCK_REALTIME as it hands it to DdsPosePublisher::publish() (queue,
# publisher thread, Cyclone DDS write) and agvslam-echo takes the receive time; the echo's summary gives median,
# p95, p99 and max of (receive - stamp) over every sample of the three topics.
#
#   tests/drivers/dds_latency.sh [--record] [BUILD_DIR] [SAMPLES] [RATE_HZ]     (defaults: build/release 2000 20)
#
# Needs `unshare -n` (root, or unprivileged user namespaces).
set -euo pipefail
source "$(dirname "$0")/../bench/record.sh"
record_init "$0" "$@"
[[ ${1:-} == --record ]] && { record=1; shift; }
build=${1:-build/release}
n=${2:-2000}
rate=${3:-20}
bin=$(cd "$build" && pwd)/bin
out=$(mktemp -d /tmp/agvslam-dds-latency.XXXXXX)
ns="unshare -n"
unshare -n true 2>/dev/null || ns="unshare -rn"
$ns sh -c "ip link set lo up &&
  ($bin/agvslam-echo --json --interface lo --count $((3 * n)) --timeout $((n / rate + 60)) --summary $out/summary.json \
     > $out/echo.jsonl 2> $out/echo.err &
   $bin/agvslam-pose-replay --synthetic $n --rate $rate --dds --interface lo --wait-subscribers 1 \
     > /dev/null 2> $out/replay.err; wait)"
record_start
cat "$out/summary.json"
echo "dds_latency: $n samples x 3 topics at $rate Hz; logs in $out"
record_finish "dds_latency" "DDS publish -> receive between two processes on loopback"
