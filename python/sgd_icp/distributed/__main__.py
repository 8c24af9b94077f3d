"""python -m sgd_icp.distributed PAIRS_FILE...: register the pairs files on a Dask cluster.

Prints one line per pair (in file order) and a summary; --csv writes the rows. See
docs/distributed.md.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import math
import os
import sys
import time

import sgd_icp

from . import PairResult, _check_settings, _run_jobs, read_jobs

CSV_FIELDS = [
    "pairs_file", "line", "source", "reference", "method", "ok", "error", "translation_error_m",
    "rotation_error_deg", "converged", "stop_reason", "degenerate", "iterations",
    "points_processed", "inlier_rmse_m", "time_ms", "build_ms", "reference_cached", "worker",
    "T_reference_source",
]


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="python -m sgd_icp.distributed",
        description="Register every pair of pairs files (the format of `sgdicp bench`, "
        "shared/data/PAIRS.md) on a Dask cluster; each starts from the identity.",
    )
    p.add_argument("pairs_files", nargs="+", metavar="PAIRS_FILE")
    p.add_argument("--scheduler", default="local", metavar="ADDRESS|local",
                   help="a dask scheduler's address (tcp://host:8786), or 'local' for a "
                   "LocalCluster on this machine (default: local)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="workers of the local cluster (default: the cores); ignored with "
                   "--scheduler ADDRESS")
    p.add_argument("--method", default="sgd", help="as sgd_icp.register / sgdicp --method "
                   "(default: sgd)")
    p.add_argument("--seed", type=int, default=None, help="random seed of the SGD methods "
                   "(default: the library's)")
    p.add_argument("--retries", type=int, default=2,
                   help="times a task that raised an unexpected error is run again (default: 2); a "
                   "task whose worker is lost is rescheduled by Dask's scheduler anyway")
    p.add_argument("--csv", metavar="FILE", help="write one CSV row per pair to FILE")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        p.error("--workers must be at least 1")
    if args.retries < 0:
        p.error("--retries must be at least 0")
    return args


def fmt(value, digits=3):
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return f"{value:.{digits}g}"


def print_row(file: str, row: PairResult) -> None:
    name = f"{os.path.basename(row.source)} <- {os.path.basename(row.reference)}"
    if not row.ok:
        print(f"{row.index + 1:<5} {name[:40]:<40} FAILED {row.error}")
        return
    print(f"{row.index + 1:<5} {name[:40]:<40} {fmt(row.translation_error_m):>10} "
          f"{fmt(row.rotation_error_deg):>10} {fmt(row.time_ms + row.build_ms, 4):>9} "
          f"{'yes' if row.converged else 'no':>4}")


def write_csv(path: str, method: str, results) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(CSV_FIELDS)
        for file, row in results:
            T = "" if row.T_reference_source is None else " ".join(
                f"{v:.17g}" for v in row.T_reference_source.reshape(-1))
            values = {"pairs_file": file, "method": method, "T_reference_source": T}
            w.writerow([values[k] if k in values else
                        ("" if getattr(row, k) is None else getattr(row, k)) for k in CSV_FIELDS])


def main(argv=None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    settings = {} if args.seed is None else {"seed": args.seed}
    try:
        files, jobs = [], []
        for file in args.pairs_files:  # a bad pairs file stops here, before a cluster starts
            for job in read_jobs(file):
                files.append(file)
                jobs.append(dataclasses.replace(job, index=len(jobs)))
        _check_settings(args.method, settings)
    except (sgd_icp.Error, OSError, TypeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    from distributed import Client

    from . import local_client

    client = (local_client(args.workers) if args.scheduler == "local"
              else Client(args.scheduler))
    start = time.perf_counter()
    try:
        rows = _run_jobs(jobs, client, args.method, settings, retries=args.retries,
                         progress=not args.no_progress)
        elapsed = time.perf_counter() - start
    finally:
        cluster = client.cluster if args.scheduler == "local" else None
        client.close()
        if cluster is not None:
            cluster.close()
    if not args.no_progress:
        print()
    print(f"{'#':<5} {'pair (source <- reference)':<40} {'t_err[m]':>10} {'r_err[deg]':>10} "
          f"{'time[ms]':>9} {'conv':>4}")
    results = list(zip(files, rows))
    for file, row in results:
        print_row(file, row)
    failed = sum(not row.ok for _, row in results)
    workers = args.workers if args.scheduler == "local" else None
    print(f"{len(results)} pairs, {failed} failed, {elapsed:.1f} s wall "
          f"({len(results) / elapsed:.2f} pairs/s"
          f"{f', {workers} workers' if workers else ''})")
    if args.csv:
        write_csv(args.csv, args.method, results)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
