#!/usr/bin/env python3
"""Search-structure build time of the peers on the micro-benchmarks' reference clouds.

usage: bench/kdtree_build_peers.py [--reps 20]
Times small_gicp.KdTree(points, num_threads=1) (and with all threads) and Open3D's
KDTreeFlann on the reference cloud of each micro-benchmark dataset (bench/bench_data.hpp), in a
warm process, median of --reps builds, for comparison with `sgdicp_micro_kdtree`'s
kdtree_build/DATASET (issue 6 target: our build no slower than small_gicp's KdTree).
Clouds are read with sgd_icp.read_points (the CLI's readers; needs `pip install .`).
"""
import argparse
import os
import statistics
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
try:
    import sgd_icp
    from peers import read_pairs  # bench/peers/, beside this script
except ImportError as e:
    sys.exit(f"bench/kdtree_build_peers.py needs the sgd_icp Python package ({e}): "
             "run `pip install .` in the repository (docs/python.md)")
import numpy as np  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

DATASETS = [("kitti", "kitti_seq00.txt"), ("kinect", "pcl_kinect_frames.txt"),
            ("car", "libpointmatcher_car.txt"), ("eth", "eth_kinect_map_moved_copies.txt")]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--data", default=os.environ.get("SGDICP_DATA", os.path.join(REPO, "..", "shared", "data")))
    args = ap.parse_args()
    import small_gicp
    try:
        import open3d as o3d
    except ImportError:
        o3d = None
    print("| dataset | points | small_gicp KdTree 1 thread [ms] | small_gicp KdTree all threads [ms] | Open3D KDTreeFlann [ms] |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for name, pf in DATASETS:
        path = os.path.join(args.data, "pairs", pf)
        if not os.path.exists(path):
            continue
        ref = read_pairs(path)[0].reference
        pts = sgd_icp.read_points(ref).astype(np.float64)
        pc = small_gicp.PointCloud(pts)

        def med(fn):
            fn()  # warm-up
            ts = []
            for _ in range(args.reps):
                t0 = time.perf_counter()
                fn()
                ts.append((time.perf_counter() - t0) * 1e3)
            return statistics.median(ts)

        t1 = med(lambda: small_gicp.KdTree(pc, num_threads=1))
        tn = med(lambda: small_gicp.KdTree(pc, num_threads=os.cpu_count()))
        to = float("nan")
        if o3d:
            opc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
            to = med(lambda: o3d.geometry.KDTreeFlann(opc))
        print(f"| {name} | {len(pts)} | {t1:.2f} | {tn:.2f} | {to:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
