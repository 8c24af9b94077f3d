#!/usr/bin/env bash
# End-to-end tests of the sgdicp command-line tool. Run by CTest with
#   SGDICP_BIN          the sgdicp executable
#   SGDICP_SHARED_DATA  the shared data folder (checks on real data are skipped when absent)
#   SGDICP_DEMO_DATA    the demo data folder (optional)
# Prints one line per check and a final "N passed, M failed"; exits 1 on any failure.
set -u

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
# CLI11 help text, one per line.
option_entries() {
  awk '
    /^Options:/ { in_options = 1; next }
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

# --- help -------------------------------------------------------------------------------------
SETTINGS_OPTIONS=(--preset --optimizer --learning-rate --batch-size --max-distance
  --max-distance-unit --max-iterations --seed)

run --help
if [ "$rc" -eq 0 ] && grep -q 'register' "$tmp/out" && grep -q 'bench' "$tmp/out"; then
  pass "sgdicp --help exits 0 and lists register and bench"
else
  fail "sgdicp --help (exit $rc)"
fi
expect_ok "sgdicp --version" --version
# One version: the CLI's is the CMake project's (CMakeLists.txt), as the Python package's is.
project_version=$(sed -n 's/^project(sgdicp VERSION \([0-9.]*\).*/\1/p' "$(dirname "$0")/../CMakeLists.txt")
if [ -n "$project_version" ] && [ "$(cat "$tmp/out")" = "sgdicp $project_version" ]; then
  pass "sgdicp --version is the CMake project version $project_version"
else
  fail "sgdicp --version printed '$(cat "$tmp/out")', CMakeLists.txt has '$project_version'"
fi

run register --help
if [ "$rc" -eq 0 ]; then
  pass "sgdicp register --help exits 0"
  cp "$tmp/out" "$tmp/register_help"
  check_help "register --help" "$tmp/register_help" --init --json --output --aligned \
    "${SETTINGS_OPTIONS[@]}"
  # Units of the settings that have one.
  for spec in "--max-distance:scaled" "--learning-rate:scaled" "--translation-tolerance:scaled" \
    "--rotation-tolerance:rad" "--max-distance-unit:m"; do
    opt="${spec%%:*}"
    unit="${spec#*:}"
    if entry_of "$tmp/register_help" "$opt" | grep -qw -- "$unit"; then
      pass "register --help: $opt states its unit ($unit)"
    else
      fail "register --help: $opt does not state its unit ($unit)"
    fi
  done
else
  fail "sgdicp register --help (exit $rc)"
fi

run bench --help
if [ "$rc" -eq 0 ]; then
  pass "sgdicp bench --help exits 0"
  cp "$tmp/out" "$tmp/bench_help"
  check_help "bench --help" "$tmp/bench_help" --perturb --csv --repeat "${SETTINGS_OPTIONS[@]}"
else
  fail "sgdicp bench --help (exit $rc)"
fi

expect_error "no subcommand" 'subcommand|required|help'

# --- synthetic clouds (no shared data needed) ---------------------------------------------------
# A deterministic, non-symmetric cloud of 800 points in about 1 m, and a copy moved by d.
awk 'BEGIN {
  for (i = 0; i < 800; i++) {
    u = (i * 0.6180339887) % 1; v = (i * 0.7548776662) % 1; w = (i * 0.5698402910) % 1
    printf "%.6f %.6f %.6f\n", u, 0.7 * v + 0.1 * sin(6 * u), 0.4 * w + 0.2 * u * u
  }
}' >"$tmp/ref.xyz"
awk '{ printf "%.6f %.6f %.6f\n", $1 + 0.02, $2 - 0.01, $3 + 0.015 }' "$tmp/ref.xyz" >"$tmp/moved.xyz"
printf '0 0 0\n1 0 0\n0 1 0\n' >"$tmp/three.xyz"
printf 'nan nan nan\nnan 1 2\n1 nan 2\n' >"$tmp/nan.xyz"
printf 'hello world foo\nbar baz qux\n1 2\n' >"$tmp/garbage.xyz"
: >"$tmp/empty.xyz"
: >"$tmp/empty.pcd"
printf '0123456789' >"$tmp/truncated.bin"
mkdir -p "$tmp/folder.pcd"
REF="$tmp/ref.xyz"
MOVED="$tmp/moved.xyz"
IDENTITY12="1 0 0 0 0 1 0 0 0 0 1 0"

run register "$MOVED" "$REF" --output "$tmp/synthetic_T.txt"
if [ "$rc" -eq 0 ] && is_4x4_matrix "$tmp/synthetic_T.txt"; then
  # source = reference + d, so T_reference_source translates by -d.
  if awk 'NR == 1 { a = $4 + 0.02 } NR == 2 { b = $4 - 0.01 } NR == 3 { c = $4 + 0.015 }
          END { e = sqrt(a * a + b * b + c * c); exit !(e < 2e-3) }' "$tmp/synthetic_T.txt"; then
    pass "register recovers a known 2.7 cm shift of a synthetic cloud"
  else
    fail "register on a synthetic shift: translation off: $(tr '\n' ' ' <"$tmp/synthetic_T.txt")"
  fi
else
  fail "register on synthetic clouds (exit $rc): $(head -c 400 "$tmp/err")"
fi

# Same inputs and seed: the same bits.
run register "$MOVED" "$REF" --output "$tmp/synthetic_T2.txt"
if [ "$rc" -eq 0 ] && cmp -s "$tmp/synthetic_T.txt" "$tmp/synthetic_T2.txt"; then
  pass "register is reproducible (same seed, identical output file)"
else
  fail "register is not reproducible with the same seed"
fi
expect_ok "register --seed 7 runs" register "$MOVED" "$REF" --seed 7

# --- error handling ------------------------------------------------------------------------------
expect_error "missing source file" 'no such|cannot open|not found|missing' \
  register "$tmp/does_not_exist.pcd" "$REF"
expect_error "missing reference file" 'no such|cannot open|not found|missing' \
  register "$REF" "$tmp/does_not_exist.xyz"
expect_error "a directory as source file" 'director' register "$tmp/folder.pcd" "$REF"
expect_error "an empty .xyz file" 'empty|no (finite )?points' register "$tmp/empty.xyz" "$REF"
expect_error "an empty .pcd file" 'empty|header|truncated' register "$tmp/empty.pcd" "$REF"
expect_error "a truncated .bin (10 bytes)" 'truncat|multiple|size' \
  register "$tmp/truncated.bin" "$REF"
expect_error "a garbage .xyz" 'number|line' register "$tmp/garbage.xyz" "$REF"
cp "$REF" "$tmp/cloud.abc"
expect_error "an unknown file extension" 'extension|format' register "$tmp/cloud.abc" "$REF"
expect_error "--batch-size 0" 'batch' register "$MOVED" "$REF" --batch-size 0
expect_error "--learning-rate -1" 'learning' register "$MOVED" "$REF" --learning-rate -1
expect_error "--max-distance 0" 'distance' register "$MOVED" "$REF" --max-distance 0
expect_error "--max-distance-unit parsec" 'max-distance-unit|parsec' \
  register "$MOVED" "$REF" --max-distance-unit parsec
expect_error "--optimizer nonsense" 'optimizer|nonsense' register "$MOVED" "$REF" --optimizer nonsense
expect_error "--init with 5 numbers" '12|16|numbers' register "$MOVED" "$REF" --init "1 2 3 4 5"
expect_error "--init with a non-rigid matrix" 'rigid' \
  register "$MOVED" "$REF" --init "2 0 0 0 0 2 0 0 0 0 2 0"
expect_error "--init with a NaN" 'finite|nan' \
  register "$MOVED" "$REF" --init "1 0 0 nan 0 1 0 0 0 0 1 0"
expect_error "--init with a missing file" 'no such|cannot open|not found' \
  register "$MOVED" "$REF" --init no_such_transform_file.txt
# A mistyped path with digits must say the file is missing, not fail to parse it as numbers.
expect_error "--init with a missing file whose name has digits" 'no such|cannot open|not found' \
  register "$MOVED" "$REF" --init "poses/T_001.txt"
expect_error "an unknown option" 'bogus' register "$MOVED" "$REF" --bogus-option
expect_error "a missing positional argument" 'REFERENCE|required' register "$MOVED"
expect_error "a source with fewer points than --batch-size" 'fewer|batch' \
  register "$tmp/three.xyz" "$REF"
expect_error "a source of only NaN points" 'finite|nan|no points|empty' register "$tmp/nan.xyz" "$REF"
expect_error "a reference of only NaN points" 'finite|nan|no points|empty' \
  register "$MOVED" "$tmp/nan.xyz"
expect_error "--output into a missing folder" 'cannot|no such|open|write' \
  register "$MOVED" "$REF" --output "$tmp/no/such/folder/T.txt"

# Every numeric option is range-checked with its name and valid range (settings.hpp's table):
# absurd values neither crash (bad_alloc), wrap around nor return the initial pose as converged.
expect_error "--window 1000000000" '^sgdicp: error: --window 1000000000: must be in \[8, 100000\]' \
  register "$MOVED" "$REF" --window 1000000000
expect_error "--window 2^64 does not wrap" '--window 18446744073709551616: must be in' \
  register "$MOVED" "$REF" --window 18446744073709551616
for opt in --max-iterations --seed --refine-stages --evaluation-points; do
  expect_error "$opt -1" "$opt -1: not a non-negative integer" register "$MOVED" "$REF" "$opt" -1
  expect_error "$opt 2^64" "$opt 18446744073709551616: must be in" \
    register "$MOVED" "$REF" "$opt" 18446744073709551616
done
expect_error "--learning-rate 1e-308" '--learning-rate 1e-308: must be in \[1e-06, 10000\]' \
  register "$MOVED" "$REF" --learning-rate 1e-308
expect_error "--epsilon 1e308" '--epsilon 1e\+308: must be in \(0, 1\]' \
  register "$MOVED" "$REF" --epsilon 1e308
expect_error "--kernel-scale 1e-308 --kernel huber" '--kernel-scale 1e-308 scaled: must be in' \
  register "$MOVED" "$REF" --kernel-scale 1e-308 --kernel huber
expect_error "--kernel-scale 1e-9 m" '--kernel-scale 1e-09 m: must be in \[1e-06, 1000000\] m' \
  register "$MOVED" "$REF" --kernel-scale 1e-9 --max-distance-unit m
expect_error "--damping 1e308 (icp-plane)" '--damping 1e\+308: must be in \[0, 100\]' \
  register "$MOVED" "$REF" --method icp-plane --damping 1e308
expect_error "--distance-factor 1e-308" '--distance-factor 1e-308: must be in \[1, 1000\]' \
  register "$MOVED" "$REF" --distance-factor 1e-308
expect_error "--max-distance 1e400" '--max-distance 1e400: must be in' \
  register "$MOVED" "$REF" --max-distance 1e400
expect_error "--learning-rate nan" '--learning-rate nan: must be in' \
  register "$MOVED" "$REF" --learning-rate nan
expect_error "--batch-size 1.5" '--batch-size 1.5: not a non-negative integer' \
  register "$MOVED" "$REF" --batch-size 1.5
expect_error "--batch-size x --window too large" '--batch-size x --window' \
  register "$MOVED" "$REF" --batch-size 100000 --window 10000
expect_error "--scaling-origin middle" '--scaling-origin: unknown scaling origin .middle.' \
  register "$MOVED" "$REF" --scaling-origin middle
expect_error "--preconditioner contradicting --optimizer" 'contradicts --optimizer adam' \
  register "$MOVED" "$REF" --preconditioner gauss-newton --optimizer adam
# Accepted spellings of the same choice give the same bits.
run register "$MOVED" "$REF" --scaling-origin corner --output "$tmp/corner_T.txt"
run register "$MOVED" "$REF" --scaling-origin lower-corner --output "$tmp/lower_corner_T.txt"
run register "$MOVED" "$REF" --scaling-origin lower_corner --output "$tmp/lower_corner2_T.txt"
if [ "$rc" -eq 0 ] && cmp -s "$tmp/corner_T.txt" "$tmp/lower_corner_T.txt" &&
  cmp -s "$tmp/corner_T.txt" "$tmp/lower_corner2_T.txt"; then
  pass "--scaling-origin corner, lower-corner and lower_corner are the same origin"
else
  fail "--scaling-origin spellings differ (exit $rc)"
fi
# The default (`sgd`) is a point-to-point coarse stage and point-to-plane refinement: the same
# as sgd-plane with --coarse-cost point-to-point, and not the same as sgd-plane (plane throughout).
run register "$MOVED" "$REF" --output "$tmp/default_T.txt"
run register "$MOVED" "$REF" --method sgd-plane --coarse-cost point-to-point --output "$tmp/hybrid_T.txt"
run register "$MOVED" "$REF" --method sgd-plane --output "$tmp/plane_T.txt"
if [ "$rc" -eq 0 ] && cmp -s "$tmp/default_T.txt" "$tmp/hybrid_T.txt" &&
  ! cmp -s "$tmp/default_T.txt" "$tmp/plane_T.txt"; then
  pass "--coarse-cost after --method sgd-plane sets the first stage's cost"
else
  fail "--method sgd-plane --coarse-cost point-to-point is not the default (exit $rc)"
fi
# One table of step sizes: --preset paper with --optimizer gauss-newton and with
# --preconditioner gauss-newton are the same run (they ran 100x apart in step size before).
run register "$MOVED" "$REF" --preset paper --optimizer gauss-newton --trace "$tmp/gn_opt.csv"
run register "$MOVED" "$REF" --preset paper --preconditioner gauss-newton --trace "$tmp/gn_pre.csv"
if [ "$rc" -eq 0 ] && cmp -s "$tmp/gn_opt.csv" "$tmp/gn_pre.csv" &&
  [ "$(sed -n 2p "$tmp/gn_opt.csv" | cut -d, -f3)" = "1" ]; then
  pass "--preset paper: --optimizer gauss-newton = --preconditioner gauss-newton, step 1"
else
  fail "--preset paper gauss-newton: the two spellings differ or the step is not 1"
fi

# Transform options name themselves in their errors.
expect_error "--ground-truth with 5 numbers names --ground-truth" '^sgdicp: error: --ground-truth' \
  register "$MOVED" "$REF" --ground-truth "1 2 3 4 5"
expect_error "--init with an inline NaN is not a missing file" '^sgdicp: error: --init: .*non-finite' \
  register "$MOVED" "$REF" --init "nan 0 0 0 0 1 0 0 0 0 1 0"
# NaN and infinity: every kind of floating option (a real, a scaled and a metric distance, a
# batch setting, a preprocessing option) and an --init file holding one are refused by name.
for bad in nan inf -inf; do
  for spec in "--learning-rate" "--max-distance" "--kernel-scale" "--trim" \
    "--translation-tolerance" "--voxel-size" "--random-ratio"; do
    expect_error "$spec $bad" "^sgdicp: error: $spec $bad( scaled)?: must be in" \
      register "$MOVED" "$REF" "$spec" "$bad"
  done
  expect_error "--max-distance $bad in metres" "^sgdicp: error: --max-distance $bad m: must be in" \
    register "$MOVED" "$REF" --max-distance "$bad" --max-distance-unit m
  expect_error "--damping $bad (icp-plane)" "^sgdicp: error: --damping $bad: must be in" \
    register "$MOVED" "$REF" --method icp-plane --damping "$bad"
  printf '1 0 0 0\n0 1 0 %s\n0 0 1 0\n0 0 0 1\n' "$bad" >"$tmp/init_$bad.txt"
  expect_error "--init file with $bad" '^sgdicp: error: --init: .*non-finite' \
    register "$MOVED" "$REF" --init "$tmp/init_$bad.txt"
done
expect_error "--init with a directory" '--init .*: a directory, not a transform file' \
  register "$MOVED" "$REF" --init "$tmp"
expect_error "--ground-truth with a directory" '--ground-truth .*: a directory' \
  register "$MOVED" "$REF" --ground-truth "$tmp"
expect_error "--init '0.0.5 ...' says which number is wrong" \
  "^sgdicp: error: --init: line 1: expected a number, got '0.0.5'" \
  register "$MOVED" "$REF" --init "0.0.5 0 0 0 0 1 0 0 0 0 1 0"
expect_error "--ground-truth '+-1 ...' is an error, not -1" \
  "^sgdicp: error: --ground-truth: line 1: expected a number, got '\\+-1'" \
  register "$MOVED" "$REF" --ground-truth "+-1 0 0 0 0 1 0 0 0 0 1 0"
if [ -e /dev/zero ]; then
  ln -sf /dev/zero "$tmp/zero.bin"
  expect_error "a source that is a symlink to /dev/zero" 'zero.bin: a character device' \
    register "$tmp/zero.bin" "$REF"
  expect_error "--init that is a symlink to /dev/zero" '^sgdicp: error: --init: .*not a regular file' \
    register "$MOVED" "$REF" --init "$tmp/zero.bin"
fi
expect_error "--picture x.jpg is refused (PNG only)" '--picture .*x.jpg: .*PNG.*\.png' \
  register "$MOVED" "$REF" --picture "$tmp/x.jpg"
if [ ! -e "$tmp/x.jpg" ]; then
  pass "--picture x.jpg writes nothing"
else
  fail "--picture x.jpg wrote a file"
fi
run register "$MOVED" "$REF" --picture "$tmp/pic.PNG"
if [ "$rc" -eq 0 ] && [ "$(head -c 4 "$tmp/pic.PNG" | tail -c 3)" = "PNG" ]; then
  pass "--picture pic.PNG writes PNG data"
else
  fail "--picture pic.PNG (exit $rc): $(head -c 300 "$tmp/err")"
fi

# --init inline and from a file, on synthetic data.
expect_ok "--init with 12 inline numbers" register "$MOVED" "$REF" --init "$IDENTITY12"
expect_ok "--init with 16 inline numbers, commas" register "$MOVED" "$REF" \
  --init "1,0,0,-0.02, 0,1,0,0.01, 0,0,1,-0.015, 0,0,0,1"
printf '# a 3x4 transform\n1 0 0 -0.02\n0 1 0 0.01\n0 0 1 -0.015\n' >"$tmp/init.txt"
expect_ok "--init with a 3x4 file" register "$MOVED" "$REF" --init "$tmp/init.txt"

# --- the bunny pair from the shared data ---------------------------------------------------------
BUNNY_SRC="${SHARED}/pcl_bunny/bun4.pcd"
BUNNY_REF="${SHARED}/pcl_bunny/bun0.pcd"
BUNNY_PAIRS="${SHARED}/pairs/pcl_bunny.txt"
if [ -z "$SHARED" ] || [ ! -f "$BUNNY_SRC" ] || [ ! -f "$BUNNY_REF" ] || [ ! -f "$BUNNY_PAIRS" ]; then
  skip "shared data checks: ${SHARED:-SGDICP_SHARED_DATA unset} has no pcl_bunny data"
else
  run register "$BUNNY_SRC" "$BUNNY_REF" --json
  if [ "$rc" -ne 0 ]; then
    fail "register --json on the bunny (exit $rc): $(head -c 400 "$tmp/err")"
  else
    pass "register --json on the bunny exits 0"
    cp "$tmp/out" "$tmp/bunny.json"
    if [ "$have_python" -eq 1 ]; then
      if python3 -c '
import json, sys
d = json.load(sys.stdin)
t = d["transform"]
assert isinstance(t, list) and len(t) == 4, "transform is not 4 rows"
assert all(isinstance(r, list) and len(r) == 4 for r in t), "transform rows are not 4 long"
assert all(isinstance(x, (int, float)) for r in t for x in r), "transform has non-numbers"
assert t[3] == [0, 0, 0, 1], "last row is not 0 0 0 1"
R = [r[:3] for r in t[:3]]
for i in range(3):
    for j in range(3):
        dot = sum(R[k][i] * R[k][j] for k in range(3))
        assert abs(dot - (1.0 if i == j else 0.0)) < 1e-6, "rotation block not orthonormal"
assert isinstance(d["converged"], bool), "converged is not a bool"
assert isinstance(d["iterations"], int) and d["iterations"] > 0, "iterations"
assert isinstance(d["points_processed"], int), "points_processed"
assert d["points_processed"] >= d["iterations"], "points_processed < iterations"
assert isinstance(d["time_ms"], (int, float)) and d["time_ms"] >= 0, "time_ms"
' <"$tmp/bunny.json" 2>"$tmp/py_err"; then
        pass "register --json: transform 4x4, converged, iterations, points_processed, time_ms"
      else
        fail "register --json output: $(tail -n 1 "$tmp/py_err")"
      fi
    else
      skip "JSON parse check (python3 missing)"
    fi
  fi

  # Against the ground truth of the pairs file (loose: this is a smoke test, not a benchmark).
  gt="$(grep -v '^#' "$BUNNY_PAIRS" | grep -m1 'bun4' | cut -d' ' -f3-)"
  if [ "$have_python" -eq 1 ] && [ -n "$gt" ]; then
    run register "$BUNNY_SRC" "$BUNNY_REF" --json --ground-truth "$gt"
    if [ "$rc" -eq 0 ] && python3 -c '
import json, sys
d = json.load(sys.stdin)
assert d["translation_error_m"] < 0.01, d["translation_error_m"]
assert d["rotation_error_geodesic_deg"] < 5.0, d["rotation_error_geodesic_deg"]
' <"$tmp/out" 2>"$tmp/py_err"; then
      pass "register on the bunny lands within 1 cm / 5 deg of the ground truth"
    else
      fail "register on the bunny vs ground truth (exit $rc): $(tail -n 1 "$tmp/py_err")"
    fi
  fi

  run register "$BUNNY_SRC" "$BUNNY_REF" --output "$tmp/bunny_T.txt"
  if [ "$rc" -eq 0 ] && is_4x4_matrix "$tmp/bunny_T.txt"; then
    pass "--output writes a 4x4 matrix"
  else
    fail "--output (exit $rc): $(head -c 300 "$tmp/bunny_T.txt" 2>/dev/null)"
  fi
  # The text output prints the same matrix.
  if [ "$rc" -eq 0 ] && grep -qF "$(head -n 1 "$tmp/bunny_T.txt")" "$tmp/out"; then
    pass "the printed transform equals the --output file"
  else
    fail "the printed transform differs from the --output file"
  fi

  run register "$BUNNY_SRC" "$BUNNY_REF" --aligned "$tmp/aligned.ply"
  if [ "$rc" -eq 0 ] && [ -s "$tmp/aligned.ply" ]; then
    pass "--aligned writes a file"
    if [ "$have_python" -eq 1 ]; then
      run register "$tmp/aligned.ply" "$BUNNY_REF" --max-iterations 1 --json
      if [ "$rc" -eq 0 ] && python3 -c '
import json, sys
d = json.load(sys.stdin)
assert d["source_points"] == 361, d["source_points"]
' <"$tmp/out" 2>"$tmp/py_err"; then
        pass "the --aligned cloud reads back as a source with all 361 points"
      else
        fail "the --aligned cloud does not read back (exit $rc): $(head -c 300 "$tmp/err") $(tail -n 1 "$tmp/py_err")"
      fi
    else
      expect_ok "the --aligned cloud reads back as a source" \
        register "$tmp/aligned.ply" "$BUNNY_REF" --max-iterations 1
    fi
  else
    fail "--aligned (exit $rc): $(head -c 300 "$tmp/err")"
  fi
  run register "$BUNNY_SRC" "$BUNNY_REF" --aligned "$tmp/aligned.xyz" --max-iterations 5
  if [ "$rc" -eq 0 ] && [ "$(grep -c . "$tmp/aligned.xyz")" -ge 361 ]; then
    pass "--aligned .xyz writes every point"
  else
    fail "--aligned .xyz (exit $rc)"
  fi

  expect_ok "--init with 12 inline numbers (bunny)" \
    register "$BUNNY_SRC" "$BUNNY_REF" --init "$IDENTITY12" --max-iterations 50
  expect_ok "--init with a file written by --output" \
    register "$BUNNY_SRC" "$BUNNY_REF" --init "$tmp/bunny_T.txt" --max-iterations 50
  expect_ok "bunny with --batch-size 1000 > 361 points: capped to the source" \
    register "$BUNNY_SRC" "$BUNNY_REF" --batch-size 1000
  expect_error "bunny with --batch-size 1000 > 361 points, uncapped" 'fewer|batch' \
    register "$BUNNY_SRC" "$BUNNY_REF" --batch-size 1000 --cap-batch-to-source false

  # bench
  run bench "$BUNNY_PAIRS" --csv "$tmp/bench.csv"
  if [ "$rc" -eq 0 ] && grep -qi 'success' "$tmp/out"; then
    pass "bench prints a summary with the success rate"
  else
    fail "bench (exit $rc): $(head -c 400 "$tmp/err")"
  fi
  if [ -f "$tmp/bench.csv" ] && [ "$(grep -c . "$tmp/bench.csv")" -eq 2 ] &&
    head -n 1 "$tmp/bench.csv" | grep -q 'translation_error' &&
    awk -F, 'NR == 1 { n = NF } NR == 2 { exit (NF != n) }' "$tmp/bench.csv"; then
    pass "bench --csv writes a header and one row of the same width"
  else
    fail "bench --csv: $(head -c 600 "$tmp/bench.csv" 2>/dev/null)"
  fi

  run bench "$BUNNY_PAIRS" --perturb 0.01,0.05,7 --csv "$tmp/perturb.csv"
  if [ "$rc" -eq 0 ] && grep -qi 'success' "$tmp/out"; then
    pass "bench --perturb 0.01,0.05,7 runs"
  else
    fail "bench --perturb (exit $rc): $(head -c 400 "$tmp/err")"
  fi
  # The initial error is exactly the requested perturbation (0.01 m, 0.05 rad = 2.8648 deg).
  if awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i }
      NR == 2 { t = $col["initial_translation_error_m"]; r = $col["initial_rotation_error_deg"]
                ok = (t - 0.01)^2 < 1e-12 && (r - 2.864788976)^2 < 1e-8 }
      END { exit !ok }' "$tmp/perturb.csv" 2>/dev/null; then
    pass "bench --perturb starts exactly 0.01 m / 0.05 rad from the ground truth"
  else
    fail "bench --perturb initial error: $(tail -n 1 "$tmp/perturb.csv" 2>/dev/null)"
  fi
  expect_error "bench --perturb with one number" 'perturb' bench "$BUNNY_PAIRS" --perturb 0.01
fi

# bench errors that need no shared data.
printf 'missing_source.pcd %s %s\n' "$REF" "$IDENTITY12" >"$tmp/missing_cloud_pairs.txt"
expect_error "bench with a pairs file naming a missing cloud" 'missing_source|no such|cannot open' \
  bench "$tmp/missing_cloud_pairs.txt"
printf 'a.xyz b.xyz 1 0 0 0 0 1 0 0 0 0 1\n' >"$tmp/bad_pairs.txt"
expect_error "bench with a malformed pairs file" 'line 1' bench "$tmp/bad_pairs.txt"
expect_error "bench with a missing pairs file" 'no such|cannot open' bench "$tmp/no_pairs.txt"
# A pairs file with relative paths, resolved against its own folder.
mkdir -p "$tmp/pairs_dir"
cp "$REF" "$tmp/ref_copy.xyz"
cp "$MOVED" "$tmp/pairs_dir/moved_copy.xyz"
printf '# synthetic\nmoved_copy.xyz ../ref_copy.xyz 1 0 0 -0.02 0 1 0 0.01 0 0 1 -0.015\n' \
  >"$tmp/pairs_dir/pairs.txt"
run bench "$tmp/pairs_dir/pairs.txt" --csv "$tmp/synthetic_bench.csv"
if [ "$rc" -eq 0 ] && [ "$(grep -c . "$tmp/synthetic_bench.csv")" -eq 2 ]; then
  pass "bench resolves relative paths against the pairs file's folder"
else
  fail "bench on a relative-path pairs file (exit $rc): $(head -c 400 "$tmp/err")"
fi

# Methods, kernels and preprocessing from the command line.
for method in sgd sgd-plane sgd-gicp icp icp-plane gicp; do
  run register "$MOVED" "$REF" --method "$method" --json
  if [ "$rc" -eq 0 ] && grep -q "\"method\": \"$method\"" "$tmp/out"; then
    pass "register --method $method runs and reports its method"
  else
    fail "register --method $method (exit $rc): $(head -c 400 "$tmp/err")"
  fi
done
# --trace: one CSV row per iteration for SGD and batch methods alike.
for method in sgd icp gicp; do
  run register "$MOVED" "$REF" --method "$method" --json --trace "$tmp/trace_$method.csv"
  iterations=$(sed -n 's/.*"iterations": \([0-9]*\).*/\1/p' "$tmp/out" | head -n 1)
  rows=$(($(grep -c . "$tmp/trace_$method.csv" 2>/dev/null || echo 1) - 1))
  if [ "$rc" -eq 0 ] && [ -n "$iterations" ] && [ "$rows" -eq "$iterations" ] && [ "$rows" -gt 0 ]; then
    pass "register --method $method --trace writes one row per iteration ($rows)"
  else
    fail "register --method $method --trace (exit $rc): $rows rows for '${iterations}' iterations"
  fi
done
expect_ok "register with a kernel, trimming and downsampling" register "$MOVED" "$REF" \
  --kernel cauchy --trim 0.8 --voxel-size 0.02
expect_ok "register with the Gauss-Newton preconditioner" register "$MOVED" "$REF" \
  --preconditioner gauss-newton
expect_error "an unknown method" 'method|sgd' register "$MOVED" "$REF" --method magic
expect_error "an unknown method in a bench list" 'unknown method' \
  bench "$tmp/pairs_dir/pairs.txt" --method sgd,magic
expect_error "--trim 0" 'trim' register "$MOVED" "$REF" --trim 0
expect_error "--voxel-size -1" 'voxel' register "$MOVED" "$REF" --voxel-size -1
# --jobs: the same registrations (same seeds, so the same errors), printed in the same order.
run bench "$tmp/pairs_dir/pairs.txt" --method sgd,icp --repeat 3 --csv "$tmp/seq.csv"
run bench "$tmp/pairs_dir/pairs.txt" --method sgd,icp --repeat 3 --jobs 2 --csv "$tmp/par.csv"
if [ "$rc" -eq 0 ] && grep -q 'throughput: 6 registrations .* on 2 thread' "$tmp/out" &&
  [ "$(cut -d, -f1-10 "$tmp/seq.csv")" = "$(cut -d, -f1-10 "$tmp/par.csv")" ]; then
  pass "bench --jobs 2 gives the rows of a sequential run, in order, and its throughput"
else
  fail "bench --jobs 2 (exit $rc): $(diff <(cut -d, -f1-10 "$tmp/seq.csv") \
    <(cut -d, -f1-10 "$tmp/par.csv") | head -c 400) $(head -c 300 "$tmp/err")"
fi
expect_error "bench --jobs 0" 'jobs' bench "$tmp/pairs_dir/pairs.txt" --jobs 0
cp "$tmp/pairs_dir/pairs.txt" "$tmp/pairs_dir/pairs_bad.txt"
printf 'missing.xyz ../ref_copy.xyz 1 0 0 0 0 1 0 0 0 0 1 0\n' >>"$tmp/pairs_dir/pairs_bad.txt"
expect_error "bench --jobs 2 with a missing cloud in the second pair" 'missing|no such|cannot' \
  bench "$tmp/pairs_dir/pairs_bad.txt" --jobs 2 --repeat 4
# --threads: the threads of one registration (voxel grid passes, KD-tree build) give the same result.
run bench "$tmp/pairs_dir/pairs.txt" --method sgd,sgd-plane --repeat 2 --threads 2 --csv "$tmp/thr.csv"
run bench "$tmp/pairs_dir/pairs.txt" --method sgd,sgd-plane --repeat 2 --threads 1 --csv "$tmp/thr1.csv"
if [ "$rc" -eq 0 ] && [ "$(cut -d, -f1-10 "$tmp/thr1.csv")" = "$(cut -d, -f1-10 "$tmp/thr.csv")" ]; then
  pass "bench --threads 2 (threads per registration) gives the results of --threads 1"
else
  fail "bench --threads 2 vs 1 (exit $rc): $(head -c 300 "$tmp/err")"
fi
expect_error "register --threads 2000" 'threads' register "$MOVED" "$REF" --threads 2000
run bench "$tmp/pairs_dir/pairs.txt" --method sgd,icp,gicp --csv "$tmp/methods.csv"
if [ "$rc" -eq 0 ] && grep -q '^method ' "$tmp/out" && [ "$(grep -c . "$tmp/methods.csv")" -eq 4 ]; then
  pass "bench --method sgd,icp,gicp prints one comparison table and one CSV row per method"
else
  fail "bench --method sgd,icp,gicp (exit $rc): $(head -c 400 "$tmp/err")"
fi

# --- depth images (docs/depth.md) --------------------------------------------------------------
# A 16-bit greyscale PNG of a plane 1.5 m ahead tilted about y, written with the standard library.
if [ "$have_python" -eq 1 ]; then
  python3 - "$tmp/plane.png" "$tmp/eight.png" <<'PY'
import struct, sys, zlib
def png(path, rows, depth):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    height, width = len(rows), len(rows[0])
    fmt = ">%dH" % width if depth == 16 else "%dB" % width
    raw = b"".join(b"\0" + struct.pack(fmt, *row) for row in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, depth, 0, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
png(sys.argv[1], [[1500 + 2 * u for u in range(80)] for v in range(60)], 16)
png(sys.argv[2], [[150 for u in range(80)] for v in range(60)], 8)
PY
  run register "$tmp/plane.png" "$tmp/plane.png" --intrinsics 70,70,39.5,29.5 --method icp
  if [ "$rc" -eq 0 ] && grep -q 'depth image 80 x 60, 4800 of 4800 pixels' "$tmp/err"; then
    pass "register reads a .png depth image with --intrinsics fx,fy,cx,cy and reports its pixels"
  else
    fail "register on a depth image (exit $rc): $(head -c 400 "$tmp/err")"
  fi
  run register "$tmp/plane.png" "$tmp/plane.png" --intrinsics 70,70,39.5,29.5 --pixel-stride 4 \
    --max-depth 1.6 --method icp
  # stride 4: 20 x 15 pixels; depth 1.5 + 0.002 u m > 1.6 m for u > 50 (columns 52..76: 7 of 20)
  if [ "$rc" -eq 0 ] && grep -q '195 of 300 pixels back-projected (0 without depth, 105 out of range)' "$tmp/err"; then
    pass "--pixel-stride and --max-depth thin and cut the depth image"
  else
    fail "--pixel-stride / --max-depth (exit $rc): $(head -c 400 "$tmp/err")"
  fi
  expect_error "a depth image without intrinsics" 'needs --intrinsics' \
    register "$tmp/plane.png" "$tmp/plane.png"
  expect_error "an 8-bit PNG as a depth image" 'eight.png: an 8-bit PNG' \
    register "$tmp/eight.png" "$tmp/plane.png" --intrinsics 70,70,39.5,29.5
  expect_error "--intrinsics with fx 0" '--intrinsics: .*fx' \
    register "$tmp/plane.png" "$tmp/plane.png" --intrinsics 0,70,39.5,29.5
  expect_error "--intrinsics with three numbers" '--intrinsics: .*expected 4' \
    register "$tmp/plane.png" "$tmp/plane.png" --intrinsics 70,70,39.5
  expect_error "--pixel-stride 0" '--pixel-stride' \
    register "$tmp/plane.png" "$tmp/plane.png" --intrinsics 70,70,39.5,29.5 --pixel-stride 0
  expect_error "--depth-scale -1" '--depth-scale' \
    register "$tmp/plane.png" "$tmp/plane.png" --intrinsics 70,70,39.5,29.5 --depth-scale -1
else
  skip "depth image checks (python3 missing to write the PNGs)"
fi
run register --help
if grep -q -- '--depth-scale FLOAT .*data.s own.*\[default: 0\]' "$tmp/out" &&
  grep -q -- '--max-depth FLOAT .*m \[default: 10\]' "$tmp/out"; then
  pass "register --help gives the depth options with unit and default"
else
  fail "register --help lacks the depth options' defaults"
fi

# Two 7-Scenes frames 5 apart (100 <- 105: 4.3 cm, 1.7 deg apart), against the ground truth
# inv(P_100) P_105 of the camera-to-world pose files (the general inverse; the rotation blocks'
# det 0.9995-0.9999 moves the answer by < 0.05 deg, far below the tolerance).
SEVEN="${SHARED}/sevenscenes_redkitchen"
if [ -z "$SHARED" ] || [ ! -f "$SEVEN/frame-000105.depth.png" ] || [ "$have_python" -eq 0 ]; then
  skip "7-Scenes depth pair: no ${SEVEN} (or no python3)"
else
  gt="$(python3 - "$SEVEN/frame-000100.pose.txt" "$SEVEN/frame-000105.pose.txt" <<'PY'
import sys
def read(path):
    return [[float(x) for x in line.split()] for line in open(path) if line.strip()]
def inverse(m):
    n = len(m)
    a = [row[:] + [float(i == j) for j in range(n)] for i, row in enumerate(m)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(a[r][c]))
        a[c], a[p] = a[p], a[c]
        a[c] = [x / a[c][c] for x in a[c]]
        for r in range(n):
            if r != c:
                a[r] = [x - a[r][c] * y for x, y in zip(a[r], a[c])]
    return [row[n:] for row in a]
Pi, Pj = inverse(read(sys.argv[1])), read(sys.argv[2])
T = [[sum(Pi[r][k] * Pj[k][c] for k in range(4)) for c in range(4)] for r in range(3)]
print(" ".join("%.12g" % x for row in T for x in row))
PY
)"
  run register "$SEVEN/frame-000105.depth.png" "$SEVEN/frame-000100.depth.png" \
    --intrinsics "$SEVEN/camera-intrinsics.txt" --pixel-stride 2 --ground-truth "$gt" --json
  # Identity is 0.043 m / 1.7 deg off; the registration measured 0.010 m / 0.49 deg (dense-tracking
  # ground truth and Kinect depth noise): half the motion in each is the bound.
  if [ "$rc" -eq 0 ] && python3 -c '
import json, sys
j = json.load(open(sys.argv[1]))
sys.exit(0 if j["translation_error_m"] < 0.02 and j["rotation_error_geodesic_deg"] < 0.85 else 1)
' "$tmp/out"; then
    pass "register two 7-Scenes depth frames 5 apart: within 2 cm and 0.85 deg of the ground truth"
  else
    fail "7-Scenes depth pair (exit $rc): $(head -c 600 "$tmp/out") $(head -c 300 "$tmp/err")"
  fi
fi
# Pose uncertainty (docs/uncertainty.md).
run register "$MOVED" "$REF" --uncertainty laplace --json
if [ "$rc" -eq 0 ] && python3 -c '
import json, sys
d = json.load(sys.stdin)
for key in ("covariance", "covariance_se3"):
    m = d[key]
    assert len(m) == 6 and all(len(r) == 6 for r in m), key
    assert all(m[i][i] > 0 for i in range(6)), key
    assert all(abs(m[i][j] - m[j][i]) <= 1e-12 * (abs(m[i][j]) + 1e-30) for i in range(6) for j in range(6))
assert d["correlation_factor"] >= 1 and d["residual_sigma_m"] > 0
' <"$tmp/out"; then
  pass "register --uncertainty laplace --json writes covariance and covariance_se3 as 6x6 lists"
else
  fail "register --uncertainty laplace --json (exit $rc): $(head -c 400 "$tmp/err")"
fi
run register "$MOVED" "$REF" --uncertainty sgld --uncertainty-samples 20 --samples "$tmp/samples.txt" --json
if [ "$rc" -eq 0 ] && [ "$(grep -vc '^#' "$tmp/samples.txt")" -eq 20 ] &&
  awk '!/^#/ && NF != 6 { bad = 1 } END { exit bad }' "$tmp/samples.txt" &&
  python3 -c 'import json, sys; d = json.load(sys.stdin); assert len(d["sample_mean"]) == 6 and d["samples"] == 20' <"$tmp/out"; then
  pass "register --uncertainty sgld --samples writes one pose vector per sample"
else
  fail "register --uncertainty sgld --samples (exit $rc): $(head -c 400 "$tmp/err")"
fi
run register "$MOVED" "$REF" --uncertainty sgld --uncertainty-samples 20 --samples "$tmp/samples2.txt" --json
if [ "$rc" -eq 0 ] && cmp -s "$tmp/samples.txt" "$tmp/samples2.txt"; then
  pass "register --uncertainty sgld: the same seed gives the same samples"
else
  fail "register --uncertainty sgld is not reproducible (exit $rc)"
fi
run register "$MOVED" "$REF" --uncertainty svgd --particles 8 --svgd-iterations 30 --samples "$tmp/particles.txt" --json
if [ "$rc" -eq 0 ] && [ "$(grep -vc '^#' "$tmp/particles.txt")" -eq 8 ] && python3 -c '
import json, sys
d = json.load(sys.stdin)
modes = d["modes"]
assert len(modes) >= 1 and abs(sum(m["weight"] for m in modes) - 1) < 1e-12
for m in modes:
    assert len(m["mean"]) == 6 and len(m["covariance"]) == 6 and all(len(r) == 6 for r in m["covariance"])
assert modes[0]["covariance"] == d["covariance"] and d["samples"] == 8
' <"$tmp/out"; then
  pass "register --uncertainty svgd --json writes the modes (weight, mean, covariance) and --samples the particles"
else
  fail "register --uncertainty svgd (exit $rc): $(head -c 400 "$tmp/err") $(head -c 400 "$tmp/out")"
fi
run register "$MOVED" "$REF" --uncertainty laplace --json
if [ "$rc" -eq 0 ] && python3 -c 'import json, sys; assert "modes" not in json.load(sys.stdin)' <"$tmp/out"; then
  pass "register --uncertainty laplace --json writes no modes"
else
  fail "register --uncertainty laplace --json has modes (exit $rc)"
fi
expect_error "register --uncertainty with an unknown name" "uncertainty.*(expected none, laplace, sgld or svgd)" \
  register "$MOVED" "$REF" --uncertainty svgd2
expect_error "register --particles 0" "--particles 0: must be in" register "$MOVED" "$REF" --uncertainty svgd --particles 0
expect_error "register --svgd-step -1" "--svgd-step -1: must be in" register "$MOVED" "$REF" --uncertainty svgd --svgd-step -1
expect_error "register --svgd-step nan" "--svgd-step" register "$MOVED" "$REF" --uncertainty svgd --svgd-step nan
expect_error "register --svgd-iterations 0" "--svgd-iterations 0: must be in" register "$MOVED" "$REF" --uncertainty svgd --svgd-iterations 0
expect_error "register --samples without sgld or svgd" "--samples.*sgld or svgd" \
  register "$MOVED" "$REF" --uncertainty laplace --samples "$tmp/x.txt"
expect_error "register --uncertainty with a batch method" "--uncertainty laplace: only the SGD methods" \
  register "$MOVED" "$REF" --method icp --uncertainty laplace
expect_error "register --thinning 0" "--thinning 0: must be in" register "$MOVED" "$REF" --thinning 0
expect_error "register --sgld-step nan" "--sgld-step" register "$MOVED" "$REF" --sgld-step nan

echo "(${skipped} skipped)"
finish
