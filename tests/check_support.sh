# Sourced by the bash checks (cli_check, outputs_check, map_command, grabber_example,
# record_command): their common steps.

# start_in DIR: DIR made afresh, empty, and the current folder.
start_in() {
  rm -rf "$1" && mkdir -p "$1" && cd "$1" || exit 1
}

fail() {
  echo "FAIL: $*"
  exit 1
}

# waitlog FILE PATTERN: waits (at most 60 s) until FILE has a line matching PATTERN.
waitlog() {
  for _ in $(seq 1 600); do
    grep -q -- "$2" "$1" 2>/dev/null && return 0
    sleep 0.1
  done
  fail "no '$2' in $1 after 60 s: $(tail -5 "$1")"
}

# refused_with RC EXPECTED COMMAND...: the command exits with RC (any non-zero when RC is "any")
# and its output says EXPECTED (a fixed string). Its output is left in out.log.
refused_count=0
refused_with() {
  local rc=$1 expect=$2
  shift 2
  "$@" >out.log 2>&1
  local got=$?
  if [[ $rc == any ]]; then
    ((got != 0)) || fail "accepted: $*"
  else
    ((got == rc)) || fail "rc $got (expected $rc): $* : $(cat out.log)"
  fi
  grep -qF -- "$expect" out.log || fail "$*: no '$expect' in: $(cat out.log)"
  refused_count=$((refused_count + 1))
}

# refused EXPECTED COMMAND...: the command fails saying EXPECTED.
refused() {
  refused_with any "$@"
}
