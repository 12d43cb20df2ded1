# VM case: the CAN pose output on a real (virtual) SocketCAN bus. agvslam-pose-replay drives CanPosePublisher;
# candump -L from can-utils records the bus; can_log_check decodes the log with deploy/agvslam.dbc and requires
# every pose the driver sent, in order, every signal within half a step, Crc and Counter right.
#   1. classic frames on vcan0, `ip link set vcan0 down` / `up` mid-run: the driver counts what it could not send,
#      reopens with back-off and resumes without a restart;
#   2. the single CAN FD frame on vcan1 (MTU 72);
#   3. ENOBUFS: vcan2 behind a tiny token-bucket qdisc drops frames at enqueue; the driver counts them, never
#      blocks, and every frame it reported sent is on the bus.
. "$(dirname "$0")/lib.sh"
require_tool agvslam-pose-replay; require_tool agvslam-can-decode; require_tool can_log_check
dbc=$AGVSLAM_SOURCE/deploy/agvslam.dbc
w=$VM_LOG_DIR
modprobe vcan || die "modprobe vcan"
modprobe can-raw || die "modprobe can-raw"

# start_dump IFACE LOG: candump -L in the background until stop_dump. candump bound to one interface exits with
# "read: Network is down" when it goes down, so the down/up run records with `candump -L any` (a socket bound to
# all interfaces gets no ENETDOWN; only vcan0 exists then).
start_dump() { candump -L "$1" >"$2" 2>"$2.err" & dump=$!; sleep 0.3; }
stop_dump() { sleep 0.3; kill "$dump" 2>/dev/null; wait "$dump" 2>/dev/null; }

step "1. classic frames on vcan0 with the interface taken down and up mid-run"
ip link add dev vcan0 type vcan && ip link set vcan0 up || die "vcan0"
start_dump any "$w/can_classic.log"
"$BIN/agvslam-pose-replay" --synthetic 160 --rate 40 --can vcan0 --json >"$w/can_classic_sent.jsonl" \
  2>"$w/can_classic_replay.err" &
replay=$!
# Down once 30 poses went out (the VM's speed varies), up 0.8 s later; 160 poses at 40 Hz leave ~2 s to resume.
i=0
until [ "$(wc -l <"$w/can_classic_sent.jsonl" 2>/dev/null || echo 0)" -ge 30 ]; do
  i=$((i + 1)); [ $i -le 600 ] || die "agvslam-pose-replay sent nothing within 60 s"
  sleep 0.1
done
ip link set vcan0 down || die "ip link set vcan0 down"
echo "vcan0 down at t=$(cut -d' ' -f1 /proc/uptime)"
sleep 0.8
ip link set vcan0 up || die "ip link set vcan0 up"
echo "vcan0 up at t=$(cut -d' ' -f1 /proc/uptime)"
wait $replay || die "agvslam-pose-replay failed: $(tail -3 "$w/can_classic_replay.err")"
stop_dump
cat "$w/can_classic_replay.err"; cat "$w/can_classic.log.err"
tail -1 "$w/can_classic_sent.jsonl"
"$BIN/can_log_check" --dbc "$dbc" --log "$w/can_classic.log" --sent "$w/can_classic_sent.jsonl" --expect-outage ||
  die "classic frames: the bus does not carry what the driver sent"
grep -q '"reopens":[2-9]' "$w/can_classic_sent.jsonl" || die "expected the driver to reopen vcan0"
"$BIN/agvslam-can-decode" --dbc "$dbc" --log "$w/can_classic.log" --json >"$w/can_classic_decoded.jsonl" ||
  die "agvslam-can-decode failed"
tail -1 "$w/can_classic_decoded.jsonl"
grep -q '"crc_bad":0' "$w/can_classic_decoded.jsonl" || die "agvslam-can-decode found CRC errors"

step "2. CAN FD frame on vcan1"
ip link add dev vcan1 type vcan && ip link set vcan1 mtu 72 && ip link set vcan1 up || die "vcan1 (CAN FD)"
start_dump vcan1 "$w/can_fd.log"
"$BIN/agvslam-pose-replay" --synthetic 60 --rate 40 --can vcan1 --can-fd --json >"$w/can_fd_sent.jsonl" \
  2>"$w/can_fd_replay.err" || die "agvslam-pose-replay --can-fd failed: $(tail -3 "$w/can_fd_replay.err")"
stop_dump
head -2 "$w/can_fd.log"
"$BIN/can_log_check" --dbc "$dbc" --log "$w/can_fd.log" --sent "$w/can_fd_sent.jsonl" || die "CAN FD frames"
grep -q '"cycles_sent":60' "$w/can_fd_sent.jsonl" || die "expected all 60 FD cycles sent"

step "3. ENOBUFS: vcan2 behind a token-bucket qdisc that drops at enqueue"
ip link add dev vcan2 type vcan && ip link set vcan2 up || die "vcan2"
if modprobe sch_tbf 2>/dev/null && tc qdisc add dev vcan2 root tbf rate 8kbit burst 64 limit 64; then
  tc qdisc show dev vcan2
  start_dump vcan2 "$w/can_nobufs.log"
  "$BIN/agvslam-pose-replay" --synthetic 120 --rate 0 --can vcan2 --json >"$w/can_nobufs_sent.jsonl" \
    2>"$w/can_nobufs_replay.err" || die "agvslam-pose-replay on vcan2 failed"
  sleep 2  # let the qdisc drain what it accepted
  stop_dump
  tail -1 "$w/can_nobufs_sent.jsonl"
  grep -q '"frames_dropped_no_buffer":0,' "$w/can_nobufs_sent.jsonl" && die "expected ENOBUFS drops"
  "$BIN/can_log_check" --dbc "$dbc" --log "$w/can_nobufs.log" --sent "$w/can_nobufs_sent.jsonl" ||
    die "ENOBUFS run: the bus does not carry what the driver reported sent"
else
  echo "note: tc/sch_tbf not available in this VM; ENOBUFS step not run"
fi
echo "PASS: CAN pose frames decoded with the DBC match what was sent; down/up survived; CAN FD; ENOBUFS counted"
