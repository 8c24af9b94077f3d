#!/usr/bin/env bash
# End-to-end tests of `sgdicp bench`: summaries and --csv rows, --perturb, pairs files (relative
# paths, errors), lists of methods, --jobs and --threads.
# Run by CTest with SGDICP_BIN and SGDICP_SHARED_DATA (cli_support.sh, which this sources).
# Prints one line per check and a final "N passed, M failed"; exits 1 on any failure.
set -u

# shellcheck source-path=SCRIPTDIR source=cli_support.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_support.sh"

# --- the bunny pair from the shared data ---------------------------------------------------------
if has_bunny "bunny bench checks"; then
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

# A list of methods.
expect_error "an unknown method in a bench list" 'unknown method' \
  bench "$tmp/pairs_dir/pairs.txt" --method sgd,magic
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
run bench "$tmp/pairs_dir/pairs.txt" --method sgd,icp,gicp --csv "$tmp/methods.csv"
if [ "$rc" -eq 0 ] && grep -q '^method ' "$tmp/out" && [ "$(grep -c . "$tmp/methods.csv")" -eq 4 ]; then
  pass "bench --method sgd,icp,gicp prints one comparison table and one CSV row per method"
else
  fail "bench --method sgd,icp,gicp (exit $rc): $(head -c 400 "$tmp/err")"
fi

done_testing
