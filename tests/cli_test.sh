#!/usr/bin/env bash
# End-to-end tests of the sgdicp command-line tool: the help texts and version, and the errors
# of every kind of bad input (files, options, transforms). `register` is tested further in
# cli_register_test.sh, `bench` in cli_bench_test.sh, `odometry` in cli_odometry_test.sh.
# Run by CTest with SGDICP_BIN and SGDICP_SHARED_DATA (cli_support.sh, which this sources).
# Prints one line per check and a final "N passed, M failed"; exits 1 on any failure.
set -u

# shellcheck source-path=SCRIPTDIR source=cli_support.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_support.sh"

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

# --help: what a user of the command sets, at most 15 options, each on one line; --help-all:
# every option, grouped by the part that reads it, each with its unit and default.
for command in register odometry bench; do
  run "$command" --help
  cp "$tmp/out" "$tmp/short_help"
  entries="$(option_entries "$tmp/short_help" | wc -l)"
  if [ "$rc" -eq 0 ] && [ "$entries" -le 15 ] && grep -q -- '--help-all' "$tmp/short_help"; then
    pass "sgdicp $command --help: $entries options, --help-all among them"
  else
    fail "sgdicp $command --help (exit $rc): $entries options (at most 15), --help-all named?"
  fi
  long="$(option_entries "$tmp/short_help" | awk 'length($0) > 160' | sed -E 's/^ +//; s/ .*//' | tr '\n' ' ')"
  if [ -z "$long" ]; then
    pass "sgdicp $command --help: every help fits one line"
  else
    fail "sgdicp $command --help: help longer than one line: $long"
  fi
done

run register --help-all
if [ "$rc" -eq 0 ]; then
  pass "sgdicp register --help-all exits 0"
  cp "$tmp/out" "$tmp/register_help"
  check_help "register --help-all" "$tmp/register_help" --init --json --output --aligned \
    "${SETTINGS_OPTIONS[@]}"
  if grep -q '^Refinement:' "$tmp/register_help" && grep -q '^Uncertainty:' "$tmp/register_help"; then
    pass "register --help-all groups the settings by part"
  else
    fail "register --help-all has no Refinement or Uncertainty group"
  fi
  # Units of the settings that have one.
  for spec in "--max-distance:scaled" "--learning-rate:scaled" "--translation-tolerance:scaled" \
    "--rotation-tolerance:rad" "--max-distance-unit:m"; do
    opt="${spec%%:*}"
    unit="${spec#*:}"
    if entry_of "$tmp/register_help" "$opt" | grep -qw -- "$unit"; then
      pass "register --help-all: $opt states its unit ($unit)"
    else
      fail "register --help-all: $opt does not state its unit ($unit)"
    fi
  done
else
  fail "sgdicp register --help-all (exit $rc)"
fi

run bench --help-all
if [ "$rc" -eq 0 ]; then
  pass "sgdicp bench --help-all exits 0"
  cp "$tmp/out" "$tmp/bench_help"
  check_help "bench --help-all" "$tmp/bench_help" --perturb --csv --repeat "${SETTINGS_OPTIONS[@]}"
else
  fail "sgdicp bench --help-all (exit $rc)"
fi

expect_error "no subcommand" 'subcommand|required|help'

# --- error handling ------------------------------------------------------------------------------
# Files that are not clouds of enough finite points.
printf '0 0 0\n1 0 0\n0 1 0\n' >"$tmp/three.xyz"
printf 'nan nan nan\nnan 1 2\n1 nan 2\n' >"$tmp/nan.xyz"
printf 'hello world foo\nbar baz qux\n1 2\n' >"$tmp/garbage.xyz"
: >"$tmp/empty.xyz"
: >"$tmp/empty.pcd"
printf '0123456789' >"$tmp/truncated.bin"
mkdir -p "$tmp/folder.pcd"
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
expect_error "--damping 1e308" '--damping 1e\+308: must be in \[0, 100\]' \
  register "$MOVED" "$REF" --damping 1e308
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
expect_error "--preconditioner, gone: one spelling, --optimizer gauss-newton" \
  '--preconditioner is no longer an option' register "$MOVED" "$REF" --preconditioner gauss-newton
# A typo in an option: the nearest option of the command (a new user's first mistake).
expect_error "--vox-size, a typo" '--vox-size: did you mean --voxel-size\?' \
  register "$MOVED" "$REF" --vox-size 0.2
expect_error "odometry --max-rnge, a typo" '--max-rnge: did you mean --max-range\?' \
  odometry "$tmp" --poses-out "$tmp/p.txt" --max-rnge 50

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

# --deskew: a skewed Newer College sweep (its per-point times as a PLY `time` field, seconds)
# registered to its motion-compensated copy from the half turn between their frames; --aligned
# writes every point in input order, point i within 6 cm of the copy's point i (median; the best
# rigid fit leaves 68 cm, the best constant velocity 2.8 cm).
NEWER="$SHARED/newer_college_ouster_skewed"
if [ -f "$NEWER/raw_02.bin" ]; then
  od -An -v -f -w12 "$NEWER/raw_02.bin" >"$tmp/nc_xyz"
  od -An -v -f -w4 "$NEWER/times_02.bin" >"$tmp/nc_t"
  n=$(grep -c . "$tmp/nc_t")
  {
    printf 'ply\nformat ascii 1.0\nelement vertex %s\nproperty float x\nproperty float y\n' "$n"
    printf 'property float z\nproperty float time\nend_header\n'
    paste -d' ' "$tmp/nc_xyz" "$tmp/nc_t"
  } >"$tmp/nc_raw.ply"
  od -An -v -f -w12 "$NEWER/deskewed_02.bin" >"$tmp/nc_copy.xyz"
  printf '%s\n' "-1 0 0 0" "0 -1 0 0" "0 0 1 0" "0 0 0 1" >"$tmp/turn.txt"
  run register "$tmp/nc_raw.ply" "$tmp/nc_copy.xyz" --init "$tmp/turn.txt" --deskew --aligned "$tmp/nc_out.xyz"
  median=$(paste -d' ' "$tmp/nc_out.xyz" "$tmp/nc_copy.xyz" |
    awk '{ d = sqrt(($1 - $4) ^ 2 + ($2 - $5) ^ 2 + ($3 - $6) ^ 2); print d }' | sort -g |
    awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }')
  if [ "$rc" -eq 0 ] && grep -q 'deskew: converged' "$tmp/out" && [ "$(grep -c . "$tmp/nc_out.xyz")" -eq "$n" ] &&
    awk -v m="${median:-1}" 'BEGIN { exit !(m < 0.06) }'; then
    pass "register --deskew: a skewed sweep compensated, point i ${median} m from the copy's (median)"
  else
    fail "register --deskew (exit $rc, median ${median:-none}): $(head -c 400 "$tmp/err") $(grep deskew "$tmp/out")"
  fi
  expect_error "register --deskew of a cloud without times" 'needs each point.s time' \
    register "$tmp/nc_copy.xyz" "$tmp/nc_copy.xyz" --deskew
fi

done_testing
