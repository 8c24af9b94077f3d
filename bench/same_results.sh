#!/usr/bin/env bash
# Do two builds register every pair the same? For refactors that must not change a result.
#   bench/same_results.sh OLD_SGDICP NEW_SGDICP [PAIRS_FILE...]
# Runs `sgdicp bench` with both binaries on every pairs file (default: ../shared/data/pairs/*.txt
# and the 7-Scenes pairs of bench/make_sevenscenes_pairs.py when present), seed 3, on one and
# two threads, and the batch and GICP methods on the smaller files, then compares the CSV rows
# without their three timing columns. Prints one line per run; exits 1 if any differs.
set -uo pipefail
if [ $# -lt 2 ]; then
  echo "usage: bench/same_results.sh OLD_SGDICP NEW_SGDICP [PAIRS_FILE...]" >&2
  exit 2
fi
# Paths as given from the caller's folder, before moving to the repository's.
old=$(realpath "$1") new=$(realpath "$2")
shift 2
pairs=()
for p in "$@"; do pairs+=("$(realpath "$p")"); done
cd "$(dirname "$0")/.." || exit 2
if [ ${#pairs[@]} -eq 0 ]; then
  pairs=(../shared/data/pairs/*.txt)
  sevenscenes=../generated/sevenscenes_redkitchen/sevenscenes_redkitchen.txt
  [ -f "$sevenscenes" ] && pairs+=("$sevenscenes")
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# The CSV without build_ms, align_ms and time_ms (columns 12-14).
untimed() { cut -d, -f1-11,15- "$1"; }
status=0
run() {  # run NAME ARGS...: both binaries, compared
  local name=$1
  shift
  "$old" bench "$@" --csv "$out/old.csv" >/dev/null 2>"$out/old.err" || true
  "$new" bench "$@" --csv "$out/new.csv" >/dev/null 2>"$out/new.err" || true
  if [ ! -s "$out/old.csv" ] || [ ! -s "$out/new.csv" ]; then
    echo "FAILED  $name: $(head -c 200 "$out/old.err" "$out/new.err")"
    status=1
  elif cmp -s <(untimed "$out/old.csv") <(untimed "$out/new.csv"); then
    echo "same    $name ($(($(wc -l <"$out/new.csv") - 1)) registrations)"
  else
    echo "DIFFER  $name"
    status=1
  fi
  rm -f "$out"/*.csv
}
for p in "${pairs[@]}"; do
  name=$(basename "$p" .txt)
  for threads in 1 2; do run "$name, $threads thread(s)" "$p" --seed 3 --threads "$threads"; done
  case $name in
    pcl_bunny | libpointmatcher_car | pcl_kinect_frames)
      for m in gicp icp-plane sgd-gicp; do run "$name, --method $m" "$p" --seed 3 --method "$m"; done
      ;;
  esac
done
exit $status
