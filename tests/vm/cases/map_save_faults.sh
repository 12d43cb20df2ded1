# VM case: the saved map survives a full disk and a state folder that turns read-only, and SIGTERM under full load
# saves it in bounded time. agvslamd plays the real KITTI 06 excerpt (dataset source, dynamic off, mapping inline)
# with its map in a tmpfs mounted for the case (the VM is root with its own kernel: mounts are safe here). Pass only if
#   1. a first run builds map A and saves it (exit 0, MAP_SAVED);
#   2. disk full: a run that loads A, extends it and saves into a tmpfs with too little room left exits 1 and logs
#      "cannot save the map (... No space left on device); the previous file is unchanged", and the file is A byte
#      for byte, with no temporary file left behind;
#   3. read-only: the same when the folder is remounted read-only while the daemon runs (EROFS at the save);
#   4. SIGTERM while frames are fed as fast as they are taken: exit 0 within STOP_S (default 120 s in the emulated
#      VM), the map saved and loadable (a localisation run in it starts).
# The emulated VM tracks a KITTI frame in ~1.6 s, so each run plays a handful of frames. Takes ~2 min.
. "$(dirname "$0")/lib.sh"
require_tool agvslamd
data=$(require_data data/kitti06_f000-050) || exit $?
w=$VM_LOG_DIR
params=$AGVSLAM_SOURCE/params
stop_s=${STOP_S:-120}
state=/tmp/agvslam-state

# config FILE FRAMES MODE RATE: a dataset run of KITTI 06 frames FRAMES (A:B) with its map in $state.
config() {
  cat >"$1" <<EOF
source:
  type: dataset
  dataset: $data
  rate: $4
  frames: "$2"
stages:
  features: $params/features_kitti.yaml
  slam: $params/slam.yaml
  place: $params/place.yaml
pipeline:
  dynamic: off
  mapping: inline
  frame_rate_hz: 10
base_link:
  z_m: 1.65
dds:
  enabled: false
can:
  enabled: false
map:
  file: $state/map.agvmap
  mode: $3
  save_on_stop: true
files:
  write_dirs: $state
EOF
}
# run NAME FRAMES MODE: agvslamd to the end of the frames; its exit status.
run() {
  config "$w/$1.yaml" "$2" "$3" 0
  agvslamd --config "$w/$1.yaml" >"$w/$1.out" 2>"$w/$1.err"
}
PATH=$BIN:$PATH

step "1. map A from frames 0:5"
mkdir -p $state && mount -t tmpfs -o size=64m tmpfs $state || die "mount tmpfs on $state"
run first 0:5 map || die "the first run failed: $(tail -3 "$w/first.err")"
grep -q "^MAP_SAVED" "$w/first.out" || die "no MAP_SAVED line: $(tail -3 "$w/first.out")"
cp $state/map.agvmap "$w/map_a.agvmap"
bytes=$(stat -c %s "$w/map_a.agvmap")
echo "map A: $bytes bytes"
umount $state

step "2. disk full at the save"
# Room for map A and 16 KiB more: extending A by frames 6:10 cannot be written.
mount -t tmpfs -o size=$((bytes + 16384)) tmpfs $state || die "mount the small tmpfs"
cp "$w/map_a.agvmap" $state/map.agvmap || die "map A does not fit the small tmpfs"
run full 6:10 map
rc=$?
[ $rc -eq 1 ] || die "expected exit 1 when the map cannot be saved, got $rc: $(tail -3 "$w/full.err")"
grep -q "cannot save the map (.*No space left on device); the previous file is unchanged" "$w/full.err" ||
  die "no clear error about the full disk: $(grep -i map "$w/full.err" | tail -3)"
cmp "$w/map_a.agvmap" $state/map.agvmap || die "map A changed after the failed save"
[ ! -e $state/map.agvmap.tmp ] || die "the temporary file was left behind"
echo "ok: exit 1, $(grep -o 'cannot save the map ([^)]*)' "$w/full.err"), map A intact"
umount $state

step "3. the folder turns read-only while the daemon runs"
mount -t tmpfs -o size=64m tmpfs $state && cp "$w/map_a.agvmap" $state/map.agvmap || die "mount and copy"
config "$w/ro.yaml" 6:40 map 0.2  # 2 frames/s: still running when the folder turns read-only
agvslamd --config "$w/ro.yaml" >"$w/ro.out" 2>"$w/ro.err" &
daemon=$!
for _ in $(seq 1200); do grep -q "agvslamd: ready" "$w/ro.err" 2>/dev/null && break; sleep 0.1; done
sleep 3
mount -o remount,ro $state || die "remount read-only"
kill -TERM $daemon
wait $daemon
rc=$?
[ $rc -eq 1 ] || die "expected exit 1 when the folder is read-only at the save, got $rc: $(tail -3 "$w/ro.err")"
grep -q "cannot save the map (.*Read-only file system); the previous file is unchanged" "$w/ro.err" ||
  die "no clear error about the read-only folder: $(grep -i map "$w/ro.err" | tail -3)"
cmp "$w/map_a.agvmap" $state/map.agvmap || die "map A changed after the failed save"
echo "ok: exit 1, $(grep -o 'cannot save the map ([^)]*)' "$w/ro.err"), map A intact"
umount $state

step "4. SIGTERM under full load"
mount -t tmpfs -o size=64m tmpfs $state && cp "$w/map_a.agvmap" $state/map.agvmap || die "mount and copy"
config "$w/load.yaml" 6:50 map 0  # as fast as the pipeline takes them
agvslamd --config "$w/load.yaml" >"$w/load.out" 2>"$w/load.err" &
daemon=$!
sleep 15
kill -0 $daemon || die "agvslamd ended before SIGTERM: $(tail -3 "$w/load.err")"
t0=$(cut -d' ' -f1 /proc/uptime)
kill -TERM $daemon
wait $daemon
rc=$?
t1=$(cut -d' ' -f1 /proc/uptime)
stop=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
[ $rc -eq 0 ] || die "expected exit 0 after SIGTERM under load, got $rc: $(tail -3 "$w/load.err")"
awk -v s="$stop" -v m="$stop_s" 'BEGIN { exit !(s <= m) }' || die "stopping took $stop s (limit $stop_s s)"
grep -q "^MAP_SAVED" "$w/load.out" || die "no MAP_SAVED after SIGTERM: $(tail -3 "$w/load.err")"
cmp -s "$w/map_a.agvmap" $state/map.agvmap && die "the map was not extended"
config "$w/check.yaml" 0:0 localise 0
agvslamd --config "$w/check.yaml" >"$w/check.out" 2>"$w/check.err" ||
  die "the map saved under load does not load: $(tail -3 "$w/check.err")"
echo "ok: SIGTERM under load: exit 0 in $stop s, $(grep '^MAP_SAVED' "$w/load.out"), loads in localisation mode"
umount $state
echo "PASS"
