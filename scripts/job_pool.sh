# shellcheck shell=bash
# A small job pool for the project's scripts. Source it.
# run_pool <jobs> <command> <item>...: runs `<command> <item>` for every item, at most <jobs> at
# a time, in the background of the calling shell; prints nothing of its own and returns the
# number of items whose command failed (0 when all succeeded).
run_pool() {
  local jobs="$1" command="$2"
  shift 2
  local failed=0 running=0 item
  for item in "$@"; do
    "$command" "$item" &
    running=$((running + 1))
    if [ "$running" -ge "$jobs" ]; then
      wait -n || failed=$((failed + 1))
      running=$((running - 1))
    fi
  done
  while [ "$running" -gt 0 ]; do
    wait -n || failed=$((failed + 1))
    running=$((running - 1))
  done
  return "$failed"
}
