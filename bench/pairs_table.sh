#!/usr/bin/env bash
# Runs `sgdicp bench` with the default settings and the paper's two presets on every pairs file
# of a folder (default ../shared/data/pairs) and prints the README's results table.
# usage: bench/pairs_table.sh [PAIRS_DIR] [REPEAT]   (SGDICP=path/to/sgdicp to pick the binary)
set -euo pipefail
cd "$(dirname "$0")/.."
pairs_dir=${1:-../shared/data/pairs}
repeat=${2:-3}
bin=${SGDICP:-build/sgdicp}
out=$(mktemp -d)
args=()
for f in "$pairs_dir"/*.txt; do
  n=$(basename "$f" .txt)
  for preset in default paper-sgd paper-adam; do
    case $preset in
      default) opts=() ;;
      paper-sgd) opts=(--preset paper --optimizer sgd) ;;
      paper-adam) opts=(--preset paper --optimizer adam) ;;
    esac
    echo "bench: $n ($preset)" >&2
    "$bin" bench "$f" "${opts[@]}" --repeat "$repeat" --csv "$out/${n}_$preset.csv" >/dev/null
    args+=("$preset=$out/${n}_$preset.csv")
  done
done
python3 bench/summarize.py "${args[@]}"
