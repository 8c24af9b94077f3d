#!/usr/bin/env python3
"""Split a callgrind profile of `sgdicp register ... --json` into phases (standard library only).

usage: bench/profile_split.py CALLGRIND.OUT [REGISTER.JSON]
Runs callgrind_annotate --inclusive=yes and prints a Markdown table of instructions (Ir) for:
file reading, KD-tree build, align() split into nearest-neighbour queries and the rest, and
everything else (process start, option parsing, output). The queries of align() are further
split between the SGD loop and the final statistics in proportion to their number
(points_processed vs evaluated_points from the JSON written next to the profile); when the
binary has evaluate_alignment(), the final statistics are its measured inclusive cost.
"""
import json
import os
import re
import subprocess
import sys

PATTERNS = {
    "read": r"sgdicp::read_point_cloud\(",
    "build": r"sgdicp::ReferenceIndex::ReferenceIndex\(sgdicp::PointCloud",
    "align": r"sgdicp::align\(sgdicp::PointCloud const&, sgdicp::ReferenceIndex const&",
    "nearest": r"sgdicp::ReferenceIndex::nearest\(",
    "evaluate": r"sgdicp::evaluate_alignment\(",
}


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    path = argv[1]
    js = argv[2] if len(argv) > 2 else re.sub(r"callgrind\.(\w+)\.out$", r"register.\1.json", path)
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path],
                          capture_output=True, text=True, check=True).stdout
    total = None
    found = {}
    for line in text.splitlines():
        m = re.match(r"\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(.*)", line)
        if not m:
            continue
        ir = int(m.group(1).replace(",", ""))
        what = m.group(2)
        if what.startswith("PROGRAM TOTALS"):
            total = ir
        for key, pat in PATTERNS.items():
            if re.search(pat, what) and key not in found:
                found[key] = ir
    info = {}
    if os.path.exists(js):
        with open(js) as f:
            info = json.load(f)
    q_loop = info.get("points_processed", 0)
    q_eval = info.get("evaluated_points", 0)
    nearest = found.get("nearest", 0)
    share_loop = q_loop / (q_loop + q_eval) if q_loop + q_eval else 1.0
    loop_q = nearest * share_loop
    if "evaluate" in found:  # measured: evaluate_alignment() (inlier statistics + degeneracy check)
        final = found["evaluate"]
        final_name = (f"align(): final statistics, evaluate_alignment() ({q_eval} NN queries + "
                      "degeneracy check)")
    else:
        final = nearest * (1 - share_loop)
        final_name = "align(): queries of the final inlier statistics (est.)"
    rows = [
        ("read the two files", found.get("read", 0)),
        ("KD-tree build (ReferenceIndex constructor)", found.get("build", 0)),
        ("align(): nearest-neighbour queries of the SGD loop (est. by query count)", loop_q),
        (final_name, final),
        ("align(): everything else (sampler, input checks, gradients, optimiser, convergence test)",
         found.get("align", 0) - loop_q - final),
    ]
    other = total - sum(v for _, v in rows)
    rows.append(("rest of the process (start-up, option parsing, output)", other))
    reg = found.get("build", 0) + found.get("align", 0)
    print(f"callgrind {os.path.basename(path)}: {total / 1e6:.0f} M instructions in total; "
          f"{info.get('iterations', '?')} iterations, {q_loop} loop queries, {q_eval} evaluation queries\n")
    print("| phase | instructions [M] | share of process | share of build + align |")
    print("| --- | ---: | ---: | ---: |")
    for name, v in rows:
        in_reg = f"{100 * v / reg:.1f} %" if reg and "process" not in name and "read" not in name else "–"
        print(f"| {name} | {v / 1e6:.1f} | {100 * v / total:.1f} % | {in_reg} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
