"""The Markdown tables of the report (Table I and II, Fig. 2 and 4) and the number formats."""
from __future__ import annotations

import math
import statistics

from peers import SUCCESS_THRESHOLDS

from .config import CONFIGS, ORDER, SHORT


def fnum(x: float) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "nan"
    if x == 0:
        return "0"
    a = abs(x)
    return f"{x:.3g}" if 1e-3 <= a < 1e4 else f"{x:.2e}"


def pm(xs: list[float]) -> str:
    if not xs:
        return "-"
    m = statistics.fmean(xs)
    s = statistics.stdev(xs) if len(xs) > 1 else 0.0
    return f"{fnum(m)} ± {fnum(s)}"


def med(xs):
    return fnum(statistics.median(xs)) if xs else "-"


def col(rows, key):
    return [float(r[key]) for r in rows]


def success(r, t=SUCCESS_THRESHOLDS[0][0], deg=SUCCESS_THRESHOLDS[0][1]) -> bool:
    return float(r["translation_error_m"]) < t and float(r["rotation_error_geodesic_deg"]) < deg


def is_ok(r) -> bool:
    """A row with a result: every CLI row; a peer row whose run ended with status ok."""
    return r.get("status", "ok") == "ok"


def table_md(rows: list[dict], group_by_pairs: bool = True) -> str:
    head = ("| pairs | method | n | t err mean ± std [m] | t err median [m] | r err mean ± std [rad] "
            "| r err median [rad] | success 5 cm & 1° | time mean ± std [s] | time median [s] | passes median |")
    out = [head, "|" + " --- |" * 2 + " ---: |" * 9]
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["pairs"] if group_by_pairs else "all", r["config"]), []).append(r)
    for (pairs, config) in sorted(groups, key=lambda k: (k[0], ORDER.index(k[1]) if k[1] in ORDER else len(ORDER))):
        g = groups[(pairs, config)]
        good = [r for r in g if is_ok(r)]
        # a timed-out peer run counts with its time limit (a lower bound), as in compare_peers
        stopped = [r for r in g if r.get("status") == "timeout"]
        te, re_ = col(good, "translation_error_m"), col(good, "rotation_error_euler_rad")
        tm = [x / 1e3 for x in col(good + stopped, "time_ms")]
        passes = [float(r["points_processed"]) / float(r["source_points"]) for r in good
                  if r.get("points_processed") not in (None, "")]
        ok = sum(success(r) for r in good)
        n_failed = len(g) - len(good) - len(stopped)
        label = config + (f" ({n_failed} failed)" if n_failed else "")
        if stopped:
            label += f" ({len(stopped)} stopped at {float(stopped[0]['time_ms']) / 1e3:.0f} s)"
        out.append(f"| {pairs} | {label} | {len(g)} | {pm(te)} | {med(te)} | {pm(re_)} | {med(re_)} | "
                   f"{100 * ok / len(g):.0f} % | {pm(tm)} | {med(tm)} | {med(passes)} |")
    return "\n".join(out)


def short_label(lab: str) -> str:
    return {"libpointmatcher_car": "car", "pcl_kinect_frames": "Kinect frames",
            "eth_kinect_map_moved_copies": "ETH map copies", "kitti_seq00": "KITTI",
            "kitti_seq00_moved_copies": "KITTI copies"}.get(lab, lab)


def fig4_table(rows: list[dict]) -> str:
    out = ["| pairs | step rule | m | n | t err median [m] | r err median [rad] | success 5 cm & 1° | "
           "time median [s] | iterations median |", "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["pairs"], r["config"], r["batch_size"]), []).append(r)
    for (lab, c, m) in sorted(groups):
        g = groups[(lab, c, m)]
        out.append(f"| {lab} | {SHORT[c]} | {m} | {len(g)} | {med(col(g, 'translation_error_m'))} | "
                   f"{med(col(g, 'rotation_error_euler_rad'))} | {100 * sum(success(r) for r in g) / len(g):.0f} % | "
                   f"{med([x / 1e3 for x in col(g, 'time_ms')])} | {med(col(g, 'iterations'))} |")
    return "\n".join(out)


def fig2_table(rows: list[dict]) -> str:
    out = ["| initial error | method | n | final t err median [m] | final r err median [rad] | success 5 cm & 1° |",
           "| --- | --- | ---: | ---: | ---: | ---: |"]
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["kind"], r["bin"], r["config"]), []).append(r)
    order = list(CONFIGS)
    for (kind, b, c) in sorted(groups, key=lambda k: (k[0] == "rotation", k[1], order.index(k[2]))):
        g = groups[(kind, b, c)]
        unit = "m" if kind == "translation" else "rad"
        out.append(f"| {kind} {float(g[0]['initial_error']):.3f} {unit} | {SHORT[c]} | {len(g)} | "
                   f"{med(col(g, 'translation_error_m'))} | {med(col(g, 'rotation_error_euler_rad'))} | "
                   f"{100 * sum(success(r) for r in g) / len(g):.0f} % |")
    return "\n".join(out)
