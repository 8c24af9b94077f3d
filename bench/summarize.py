#!/usr/bin/env python3
"""Markdown table from `sgdicp bench --csv` files (standard library only).

usage: bench/summarize.py [LABEL=]FILE.csv [...]
One row per (pairs file, method) found in the files (the method column of the CSV, prefixed by
LABEL when given): median translation and rotation errors, success rates, convergence, median
time and points processed.
"""
import csv
import os
import statistics
import sys


def rows_of(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    print("| pairs | method | n | t err median [m] | r err median [deg] | r err median, sum abs d rpy [rad] "
          "| success 5 cm & 1 deg | success 2 m & 5 deg | converged | time median [ms] | points processed median (passes) |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    groups = {}
    for arg in argv[1:]:
        label, path = arg.split("=", 1) if "=" in arg else ("", arg)
        for r in rows_of(path):
            pairs = os.path.basename(r["pairs_file"]).removesuffix(".txt")
            method = r.get("method", "")
            name = " ".join(x for x in (label, method) if x) or "sgd"
            groups.setdefault((pairs, name), []).append(r)
    for (pairs, name), rows in groups.items():
        te = [float(r["translation_error_m"]) for r in rows]
        rg = [float(r["rotation_error_geodesic_deg"]) for r in rows]
        rs = [float(r["rotation_error_euler_rad"]) for r in rows]
        tm = [float(r["time_ms"]) for r in rows]
        pts = [float(r["points_processed"]) for r in rows]
        passes = [float(r["points_processed"]) / float(r["source_points"]) for r in rows]
        ok1 = sum(1 for t, r in zip(te, rg) if t < 0.05 and r < 1.0)
        ok2 = sum(1 for t, r in zip(te, rg) if t < 2.0 and r < 5.0)
        conv = sum(int(r["converged"]) for r in rows)
        n = len(rows)
        print(f"| {pairs} | {name} | {n} | {statistics.median(te):.3g} | {statistics.median(rg):.3g} | "
              f"{statistics.median(rs):.3g} | {100 * ok1 / n:.0f} % | {100 * ok2 / n:.0f} % | {conv}/{n} | "
              f"{statistics.median(tm):.3g} | {statistics.median(pts):.3g} ({statistics.median(passes):.2g}) |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
