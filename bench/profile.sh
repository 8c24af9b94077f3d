#!/usr/bin/env bash
# Where the time of one `sgdicp register` goes (issue 6): callgrind instruction counts, split into
# file reading, KD-tree build, the SGD loop's nearest-neighbour queries, the final inlier
# statistics and the rest, for a KITTI pair and the Kinect pair; plus a perf (cpu-clock) sample
# profile when perf works.
# usage: bench/profile.sh [SGDICP_BINARY] [OUT_DIR]   (default build-bench/sgdicp, results/profile)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build-bench/sgdicp}
out=${2:-results/profile}
data=${SGDICP_DATA:-../shared/data}
mkdir -p "$out"
pairs=(
  "kitti $data/kitti_odometry_seq00/velodyne/000001.bin $data/kitti_odometry_seq00/velodyne/000000.bin"
  "kinect $data/pcl_kinect_frames/frame_20121214T142256.068683.pcd $data/pcl_kinect_frames/frame_20121214T142255.814212.pcd"
)
for p in "${pairs[@]}"; do
  read -r name src ref <<<"$p"
  [[ -f $src && -f $ref ]] || { echo "skip $name: missing data" >&2; continue; }
  echo "== $name: callgrind" >&2
  valgrind --tool=callgrind --callgrind-out-file="$out/callgrind.$name.out" \
    "$bin" register "$src" "$ref" --json >"$out/register.$name.json" 2>"$out/valgrind.$name.log"
  callgrind_annotate --inclusive=yes --threshold=100 "$out/callgrind.$name.out" >"$out/inclusive.$name.txt" 2>/dev/null
  callgrind_annotate --inclusive=yes --tree=caller --threshold=100 "$out/callgrind.$name.out" >"$out/callers.$name.txt" 2>/dev/null
  python3 bench/profile_split.py "$out/callgrind.$name.out" | tee "$out/split.$name.md"
  if perf stat -e cpu-clock true >/dev/null 2>&1; then
    echo "== $name: perf record -e cpu-clock (10 runs)" >&2
    perf record -q -e cpu-clock -F 5000 -g -o "$out/perf.$name.data" -- \
      bash -c "for i in 1 2 3 4 5 6 7 8 9 10; do '$bin' register '$src' '$ref' >/dev/null; done" 2>/dev/null || true
    perf report -i "$out/perf.$name.data" --no-children --sort symbol --stdio 2>/dev/null | grep -v '^#' | grep '%' | head -25 >"$out/perf.$name.txt" || true
  fi
done
