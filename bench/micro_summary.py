#!/usr/bin/env python3
"""Markdown tables from the micro-benchmarks' JSON (standard library only).

usage: bench/micro_summary.py [--stat min|median] KDTREE.json REGISTRATION.json
       (from sgdicp_micro_kdtree / sgdicp_micro_registration --benchmark_format=json
        --benchmark_repetitions=N --benchmark_report_aggregates_only=true)
Uses the "min" aggregate (fastest repetition; robust on a busy machine) when present, else the
median, else the single run; --stat median picks the median.
"""
import json
import sys


STAT = "min"


def load(path):
    with open(path) as f:
        data = json.load(f)
    out, rank = {}, {}
    order = {STAT: 0, "median": 1, None: 2}
    for b in data["benchmarks"]:
        agg = b.get("aggregate_name") if b.get("run_type") == "aggregate" else None
        if agg not in order:
            continue
        name = b.get("run_name", b["name"])
        if name not in out or order[agg] < rank[name]:
            out[name], rank[name] = b, order[agg]
    return data.get("context", {}), out


def ms(b):
    t = b["real_time"]
    unit = b.get("time_unit", "ns")
    return t * {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[unit]


def main(argv):
    global STAT
    if "--stat" in argv:
        i = argv.index("--stat")
        STAT = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    ctx, kd = load(argv[1])
    _, reg = load(argv[2])
    datasets = []
    for name in list(kd) + list(reg):
        ds = name.split("/")[1]
        if ds not in datasets:
            datasets.append(ds)
    print(f"Machine: {ctx.get('num_cpus', '?')} CPUs at {ctx.get('mhz_per_cpu', '?')} MHz, load average "
          f"{', '.join(f'{x:.2f}' for x in ctx.get('load_avg', []))}; date {ctx.get('date', '?')}\n")
    print("| dataset | points (ref) | KD-tree build [ms] | build [ns/point] | NN query unbounded [ns] | NN query d_max 0.5 m [ns] (found) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for ds in datasets:
        b = next((v for k, v in kd.items() if k.startswith(f"kdtree_build/{ds}/")), None)
        u = kd.get(f"nearest/{ds}/unbounded")
        d = kd.get(f"nearest/{ds}/dmax_0.5m")
        if not b:
            continue
        print(f"| {ds} | {b['points']:.0f} | {ms(b):.2f} | {ms(b) * 1e6 / b['points']:.0f} | "
              f"{ms(u) * 1e6:.0f} | {ms(d) * 1e6:.0f} ({100 * d['found_fraction']:.0f} %) |")
    print()
    print("| dataset | align, 1 iteration [ms] (fixed cost) | align, 10 it. [ms] | align, 100 it. [ms] | per iteration [µs] = (t100 - t10) / 90 | per source point of a batch [ns] | full registration [ms] | of which build [ms] | align [ms] | iterations | t err [m] | r err [°] |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for ds in datasets:
        a = {n: reg.get(f"align/{ds}/iters:{n}") for n in (1, 10, 100)}
        r = next((v for k, v in reg.items() if k.startswith(f"register/{ds}/")), None)
        if not all(a.values()) or not r:
            continue
        per_it = (ms(a[100]) - ms(a[10])) / 90
        print(f"| {ds} | {ms(a[1]):.2f} | {ms(a[10]):.2f} | {ms(a[100]):.2f} | {per_it * 1e3:.1f} | {per_it * 1e6 / 160:.0f} | "
              f"{ms(r):.1f} | {r['build_ms']:.1f} | {r['align_ms']:.1f} | {r['iterations']:.0f} | {r['t_err_m']:.3g} | {r['r_err_deg']:.3g} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
