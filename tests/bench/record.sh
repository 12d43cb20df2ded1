# Sourced by the benchmark scripts. With --record a script tees what it prints into a file and, at the end, writes
# it as its section of tests/bench/RESULTS.md (record_results.py adds the command, machine and commit).
#   record_init "$0" "$@"           before the options are parsed: remembers the command line
#   record_start                    after parsing, when $record is 1: stdout goes to the terminal and the record
#   record_finish ID TITLE          at the end: writes the section (the script's output in a text block)
record=0
record_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
record_command=""
record_file=""
record_init() {
  local script=$1; shift
  record_command="tests/bench/$(basename "$script")"
  [[ $script == *tests/drivers/* ]] && record_command="tests/drivers/$(basename "$script")"
  local a
  for a in "$@"; do record_command+=" $(printf '%q' "$a")"; done
}
record_start() {
  [[ $record == 1 ]] || return 0
  record_file=$(mktemp)
  exec 3>&1
  exec > >(tee "$record_file" >&3)
  record_tee_pid=$!
}
record_finish() {
  [[ $record == 1 ]] || return 0
  exec 1>&3 3>&-  # tee sees the end of its input and finishes the file
  wait "$record_tee_pid" 2>/dev/null || true
  { echo '```text'; cat "$record_file"; echo '```'; } |
    "$record_dir/record_results.py" --id "$1" --title "$2" --command "${record_command/ --record/}"
  rm -f "$record_file"
}
