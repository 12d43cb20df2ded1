# Helpers for the scripts that run inside the VM (sourced). Environment from vm-run.sh: AGVSLAM_BUILD,
# AGVSLAM_SOURCE, AGVSLAM_SHARED_DIR, CI, VM_LOG_DIR.
set -uo pipefail
BIN=$AGVSLAM_BUILD/bin
step() { echo "=== $* (t=$(cut -d' ' -f1 /proc/uptime) s)"; }
# Messages go to stderr: a helper called as data=$(require_data ...) must still say why on the console.
die() { echo "FAIL: $*" >&2; exit 1; }
# require_data REL: the shared data set's path; exit 77 (skip) when absent, 1 under CI=true.
require_data() {
  local p=$AGVSLAM_SHARED_DIR/$1
  if [ ! -d "$p" ]; then
    if [ "${CI:-}" = "true" ]; then die "shared data $1 missing under $AGVSLAM_SHARED_DIR (CI=true)"; fi
    echo "SKIP: shared data $1 not found under $AGVSLAM_SHARED_DIR" >&2; exit 77
  fi
  echo "$p"
}
require_tool() { [ -x "$BIN/$1" ] || die "$BIN/$1 not built"; }
# wait_for FILE SECONDS
wait_for() {
  local i=0
  while [ ! -e "$1" ]; do
    i=$((i + 1)); [ $i -le $(($2 * 10)) ] || return 1
    sleep 0.1
  done
}
# expect_exit STATUS PATTERN -- COMMAND...: runs COMMAND, checks its exit status and that its output matches PATTERN.
expect_exit() {
  local want=$1 pattern=$2; shift 3
  local out rc
  out=$("$@" 2>&1); rc=$?
  echo "$out" | tail -3
  [ "$rc" -eq "$want" ] || die "expected exit $want from '$*', got $rc"
  echo "$out" | grep -q -- "$pattern" || die "expected '$pattern' in the output of '$*'"
  echo "ok: exit $rc, message has '$pattern'"
}
