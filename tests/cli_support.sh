# shellcheck shell=bash
# The variables set here are used by the scripts that source it.
# shellcheck disable=SC2034
# Shared by the end-to-end tests of the sgdicp command-line tool (cli_test.sh, cli_odometry_test.sh,
# cli_register_test.sh, cli_bench_test.sh), which source it after `set -u`. Reads
#   SGDICP_BIN          the sgdicp executable
#   SGDICP_SHARED_DATA  the shared data folder (checks on real data are skipped when absent)
# and gives the check functions (pass, fail, skip, expect_ok, expect_error, finish), a
# temporary folder $tmp removed on exit, `run` (stdout in $tmp/out, stderr in $tmp/err, status in
# $rc), the help-text checks, and the synthetic clouds $REF and $MOVED.

BIN="${SGDICP_BIN:-}"
SHARED="${SGDICP_SHARED_DATA:-}"
passed=0
failed=0
skipped=0

pass() {
  echo "PASS: $1"
  passed=$((passed + 1))
}
fail() {
  echo "FAIL: $1"
  failed=$((failed + 1))
}
skip() {
  echo "SKIP: $1"
  skipped=$((skipped + 1))
}
finish() {
  echo "${passed} passed, ${failed} failed"
  [ "$failed" -eq 0 ] || exit 1
  exit 0
}

if [ -z "$BIN" ] || [ ! -x "$BIN" ]; then
  fail "SGDICP_BIN ('${BIN}') is not an executable"
  finish
fi

tmp="$(mktemp -d "${TMPDIR:-/tmp}/sgdicp_cli_test.XXXXXX")" || {
  fail "mktemp -d"
  finish
}
trap 'rm -rf "$tmp"' EXIT

# Runs the tool with the given arguments; stdout in $tmp/out, stderr in $tmp/err, status in $rc.
rc=0
run() {
  "$BIN" "$@" >"$tmp/out" 2>"$tmp/err"
  rc=$?
}

# expect_ok NAME ARGS...: exit status 0.
expect_ok() {
  local name="$1"
  shift
  run "$@"
  if [ "$rc" -eq 0 ]; then
    pass "$name"
  else
    fail "$name (exit $rc): $(head -c 400 "$tmp/err")"
  fi
}

# expect_error NAME REGEX ARGS...: non-zero exit (not a crash) and stderr matching REGEX
# (extended, case-insensitive).
expect_error() {
  local name="$1" regex="$2"
  shift 2
  run "$@"
  if [ "$rc" -eq 0 ]; then
    fail "$name: exit status 0, expected an error"
  elif [ "$rc" -ge 128 ]; then
    fail "$name: killed by a signal (exit $rc): $(head -c 400 "$tmp/err")"
  elif ! grep -Eiq -- "$regex" "$tmp/err"; then
    fail "$name: stderr does not match /$regex/: $(head -c 400 "$tmp/err")"
  else
    pass "$name (exit $rc: $(head -n 1 "$tmp/err" | head -c 160))"
  fi
}

# True when FILE holds exactly 4 lines of 4 finite numbers whose last line is 0 0 0 1.
is_4x4_matrix() {
  awk '
    NF == 0 { next }
    {
      rows++
      if (NF != 4) bad = 1
      for (i = 1; i <= NF; i++) if ($i !~ /^[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$/) bad = 1
      if (rows == 4 && ($1 + 0 != 0 || $2 + 0 != 0 || $3 + 0 != 0 || $4 + 0 != 1)) bad = 1
    }
    END { exit (bad || rows != 4) }' "$1"
}

# The option entries ("  -x,--name ARG  description ...", continuation lines joined) of a
# CLI11 help text, one per line: those under "Options:" and under every group heading of
# --help-all ("Refinement:", "Global registration (...):"), not the positionals.
option_entries() {
  awk '
    /^Positionals:/ { in_options = 0; next }
    /^[A-Za-z].*:$/ { in_options = 1; next }
    /^[A-Za-z]/ { in_options = 0 }
    in_options && /^ +-/ { if (entry != "") print entry; entry = $0; next }
    in_options && /^ +[^ -]/ && entry != "" { entry = entry " " $0; next }
    END { if (entry != "") print entry }' "$1"
}

# check_help NAME HELP_FILE REQUIRED_OPTIONS...: every option has "[default:" in its help
# (except flags and output files, which have nothing to default to) and every required option
# appears.
check_help() {
  local name="$1" file="$2"
  shift 2
  local entries="$tmp/entries"
  option_entries "$file" >"$entries"
  if [ ! -s "$entries" ]; then
    fail "$name: no options found in the help text"
    return
  fi
  local missing_default
  missing_default="$(grep -Ev -- '^ +(-h,)?--help|^ +--version|^ +--json|^ +(-o,)?--output|^ +--aligned|^ +--picture|^ +--trace|^ +--samples|^ +--ground-truth|^ +--csv' "$entries" |
    grep -Fv '[default:' | sed -E 's/^ +//; s/ .*//' | tr '\n' ' ')"
  if [ -n "$missing_default" ]; then
    fail "$name: options without '[default:' in their help: $missing_default"
  else
    pass "$name: every option with a default shows it ($(wc -l <"$entries") options)"
  fi
  local opt absent=""
  for opt in "$@"; do
    grep -Eq -- "(^|[ ,])${opt}( |,|\$)" "$entries" || absent="$absent $opt"
  done
  if [ -n "$absent" ]; then
    fail "$name: options missing from the help:$absent"
  else
    pass "$name: mentions $*"
  fi
}

# The help entry of one option.
entry_of() {
  option_entries "$1" | grep -E -- "(^|[ ,])$2( |,|\$)"
}

have_python=0
if command -v python3 >/dev/null 2>&1 && python3 -c 'import json' >/dev/null 2>&1; then
  have_python=1
fi

# A deterministic, non-symmetric cloud of 800 points in about 1 m, and a copy moved by d.
awk 'BEGIN {
  for (i = 0; i < 800; i++) {
    u = (i * 0.6180339887) % 1; v = (i * 0.7548776662) % 1; w = (i * 0.5698402910) % 1
    printf "%.6f %.6f %.6f\n", u, 0.7 * v + 0.1 * sin(6 * u), 0.4 * w + 0.2 * u * u
  }
}' >"$tmp/ref.xyz"
awk '{ printf "%.6f %.6f %.6f\n", $1 + 0.02, $2 - 0.01, $3 + 0.015 }' "$tmp/ref.xyz" >"$tmp/moved.xyz"
REF="$tmp/ref.xyz"
MOVED="$tmp/moved.xyz"
IDENTITY12="1 0 0 0 0 1 0 0 0 0 1 0"

# The bunny pair of the shared data; has_bunny is false (and a skip recorded) when it is absent.
BUNNY_SRC="${SHARED}/pcl_bunny/bun4.pcd"
BUNNY_REF="${SHARED}/pcl_bunny/bun0.pcd"
BUNNY_PAIRS="${SHARED}/pairs/pcl_bunny.txt"
has_bunny() {
  if [ -z "$SHARED" ] || [ ! -f "$BUNNY_SRC" ] || [ ! -f "$BUNNY_REF" ] || [ ! -f "$BUNNY_PAIRS" ]; then
    skip "$1: ${SHARED:-SGDICP_SHARED_DATA unset} has no pcl_bunny data"
    return 1
  fi
}

# The last line of every test script: the skipped count, then finish.
done_testing() {
  echo "(${skipped} skipped)"
  finish
}
