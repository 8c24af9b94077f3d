#!/usr/bin/env python3
"""The time budget per stage and its floor as Markdown tables (standard library only).

usage: bench/stage_budget.py BUDGET.JSON [FLOOR.JSON]
BUDGET.JSON: sgdicp_micro_stage_budget --benchmark_repetitions=N --benchmark_format=json;
FLOOR.JSON: the same of sgdicp_micro_floor. Reads the medians of the repetitions (wall time,
ms) and derives the stages that the public API cannot run alone (micro_stage_budget.cpp):
  surfaces     = thin_surfaces - thin_reference
  beyond parts = reference_index - grid_search - thin_surfaces - tree (so that the reference's
                 rows add up to reference_index_for as measured)
  coarse stage = align_coarse - thin_source - box_source - evaluation_coarse
  refinement   = align - align_coarse - evaluation + evaluation_coarse
"""
import json
import sys

PAIRS = [("kitti", "KITTI"), ("kinect", "Kinect"), ("balm", "hand-held LiDAR (BALM)")]


def medians(path):
    """{(group, what, pair[, arg]): median real time in ms} and the counters of the runs."""
    with open(path) as f:
        data = json.load(f)
    times, counters = {}, {}
    for b in data["benchmarks"]:
        key = tuple(part for part in b["run_name"].split("/")
                    if part != "manual_time" and not part.startswith("min_time:"))
        if b.get("aggregate_name") == "median":
            times[key] = b["real_time"]
        elif b.get("run_type") == "iteration":
            counters[key] = b
    return times, counters


def stages(t, pair):
    g = lambda what: t[("budget", what, pair)]
    return [
        ("thinning (grid search, reference and source centroids)",
         g("grid_search") + g("thin_reference") + g("thin_source")),
        ("index (KD-tree over the reference centroids)", g("tree")),
        ("surfaces (3x3x3 block normals of the reference)",
         g("thin_surfaces") - g("thin_reference")),
        ("reference_index_for beyond these parts (the reused counting pass; BALM's coarser "
         "block surfaces)",
         g("reference_index") - g("grid_search") - g("thin_surfaces") - g("tree")),
        ("scaling (bulk boxes of both clouds)", g("box_source") + g("box_reference")),
        ("coarse stage (Adam, point-to-point)",
         g("align_coarse") - g("thin_source") - g("box_source") - g("evaluation_coarse")),
        ("refinement stages (Gauss-Newton, point-to-plane)",
         g("align") - g("align_coarse") - g("evaluation") + g("evaluation_coarse")),
        ("evaluation (inliers, degeneracy check)", g("evaluation")),
    ]


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    t, c = medians(argv[1])
    pairs = [p for p in PAIRS if ("budget", "end_to_end", p[0]) in t]
    floor_t, floor_c = medians(argv[2]) if len(argv) > 2 else ({}, {})
    print("| stage [ms, median] | " + " | ".join(name for _, name in pairs) + " |")
    print("| --- |" + " ---: |" * len(pairs))
    rows = {p: stages(t, p) for p, _ in pairs}
    for i, (label, _) in enumerate(rows[pairs[0][0]]):
        print(f"| {label} | " + " | ".join(f"{rows[p][i][1]:.2f}" for p, _ in pairs) + " |")
    sums = {p: sum(v for _, v in rows[p]) for p, _ in pairs}
    e2e = {p: t[("budget", "end_to_end", p)] for p, _ in pairs}
    print("| **sum of the stages** | " + " | ".join(f"**{sums[p]:.2f}**" for p, _ in pairs) + " |")
    print("| **end to end** (reference_index_for + align) | " +
          " | ".join(f"**{e2e[p]:.2f}**" for p, _ in pairs) + " |")
    print("| sum / end to end | " +
          " | ".join(f"{100 * sums[p] / e2e[p]:.0f} %" for p, _ in pairs) + " |")
    if floor_t:
        f = lambda what, p: floor_t[("floor", what, p)]
        print("| **floor**: bin the reference + the run's queries in 27 voxels | " +
              " | ".join(f"**{f('bin', p) + f('hash_queries', p):.2f}** "
                         f"({f('bin', p):.2f} + {f('hash_queries', p):.2f})" for p, _ in pairs) +
              " |")
        print("| the same queries in the KD-tree (build + queries, no NearestMemory) | " +
              " | ".join(f"{t[('budget', 'tree', p)] + f('tree_queries', p):.2f} "
                         f"({t[('budget', 'tree', p)]:.2f} + {f('tree_queries', p):.2f})"
                         for p, _ in pairs) + " |")
        print("| the same queries in the KD-tree within min(d_max, voxel), as the hash | " +
              " | ".join(f"{f('tree_queries_in_cell', p):.2f}" for p, _ in pairs) + " |")
        for k in ("1", "2"):
            key = lambda what, p: ("floor", what, p, f"cell:{k}")
            if all(key("voxel_hash", p) in floor_t for p, _ in pairs):
                print(f"| the same in ReferenceIndex::with_voxel_hash, cell {k} voxel "
                      "(build + queries) | " +
                      " | ".join(f"{floor_t[key('voxel_hash', p)] + floor_t[key('voxel_hash_queries', p)]:.2f} "
                                 f"({floor_t[key('voxel_hash', p)]:.2f} + "
                                 f"{floor_t[key('voxel_hash_queries', p)]:.2f})"
                                 for p, _ in pairs) + " |")
    print()
    for p, name in pairs:
        e = c.get(("budget", "end_to_end", p), {})
        a = c.get(("budget", "align", p), {})
        q = floor_c.get(("floor", "hash_queries", p), {})
        line = (f"- {name}: {int(e.get('source_points', 0))} source and "
                f"{int(e.get('reference_points', 0))} reference points on the grid, "
                f"{int(e.get('iterations', 0))} iterations ({int(a.get('coarse_iterations', 0))} "
                f"coarse), {int(e.get('points_processed', 0))} points processed")
        if q:
            line += (f"; {int(q['queries'])} queries, the hash finds a pair for "
                     f"{100 * q['found']:.0f} %, the tree's answer for {100 * q['same_as_tree']:.0f} %")
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
