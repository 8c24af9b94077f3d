"""Table I and II: our configurations through `sgdicp bench`, the peer libraries through the
runners of bench/compare_peers.py, and Table I on the 7-Scenes sequence."""
from __future__ import annotations

import importlib.metadata
import os
import subprocess
import sys
import time

from peers import PeerSettings, Session, build_methods, find_pcl_adapter

from .config import PEER_NAME, REPO, SEVEN_CONFIGS, SEVEN_GENERATED, SEVEN_PEERS, SEVEN_SETS, STOCHASTIC, log
from .runner import Runner, load_pairs


def exp_table(runner: Runner, pairs_files: list[str], configs: list[str], repeat: int, max_pairs: int | None,
              what: str) -> list[dict]:
    rows = []
    for pf in pairs_files:
        try:
            label, pairs = load_pairs(pf)
        except (OSError, ValueError) as e:
            runner.failures.append((f"{what}: {pf}", f"cannot read pairs file: {e}"))
            continue
        if max_pairs:
            pairs = pairs[:max_pairs]
        for c in configs:
            n = repeat if c in STOCHASTIC else 1
            log(f"{what}: {label} ({len(pairs)} pairs x {n}) {c}")
            t0 = time.perf_counter()
            rows += runner.bench(pairs, label, c, ["--repeat", str(n), "--seed", "2019"], what)
            log(f"  {time.perf_counter() - t0:.1f} s")
    return rows


class Peers:
    """The peer libraries of Table I, run by bench/peers/ (the runners of bench/compare_peers.py):
    each registration in a worker process of its library, stopped after timeout_s."""

    def __init__(self, wanted: list[str], exe: str, timeout_s: float):
        self.active: list = []                    # peers.Method that can run
        self.not_run: list[tuple[str, str]] = []  # (method, reason)
        self.versions: dict[str, str] = {}
        self.settings = PeerSettings(timeout_s=timeout_s)
        self.session = None
        if not wanted:
            return
        pcl_adapter = find_pcl_adapter(None, REPO)
        try:
            methods = {m.name: m for m in build_methods(self.settings, exe, pcl_adapter)}
        except Exception as e:  # noqa: BLE001 - a broken peer installation is recorded, not fatal
            self.not_run = [(w, f"setup failed: {e!r}") for w in wanted]
            return
        self.session = Session(self.settings, sgdicp=exe, pcl_adapter=pcl_adapter, log=log)
        for w in wanted:
            m = methods[w]
            if m.available:
                self.active.append(m)
            elif m.family in ("small_gicp", "open3d") and m.why_not.startswith("import"):
                self.not_run.append((w, "not installed: " + m.why_not.rsplit("; pip install", 1)[0]))
            else:
                self.not_run.append((w, m.why_not))
        for mod in ("small_gicp", "open3d"):
            if any(m.family == mod for m in self.active):
                try:
                    self.versions[mod] = importlib.metadata.version(mod)
                except importlib.metadata.PackageNotFoundError:
                    self.versions[mod] = "?"

    def close(self) -> None:
        if self.session is not None:
            self.session.close()


def exp_peers(runner: Runner, peers: Peers, pairs_files: list[str], max_pairs: int | None, what: str) -> list[dict]:
    """Every active peer once on every pair (the peers are deterministic from the identity start),
    after one untimed warm-up run per method; rows in the columns of `sgdicp bench --csv`."""
    if not peers.active:
        return []
    files = []
    for pf in pairs_files:
        try:
            label, pairs = load_pairs(pf)
        except (OSError, ValueError):
            continue  # recorded by exp_table
        files.append((label, pairs[:max_pairs] if max_pairs else pairs))
    everything = [p for _, ps in files for p in ps]
    log(f"{what}: peers {', '.join(PEER_NAME[m.name] for m in peers.active)}: reading clouds")
    try:
        readable = {id(p) for p in peers.session.prepare(everything, peers.active)}
    except Exception as e:  # noqa: BLE001
        peers.not_run += [(m.name, f"setup failed: {e!r}") for m in peers.active]
        peers.active = []
        return []
    rows = []
    for label, pairs in files:
        for m in peers.active:
            name = PEER_NAME[m.name]
            log(f"{what}: {label} ({len(pairs)} pairs x 1) {name}")
            t0 = time.perf_counter()
            for p in pairs:
                row = {"pairs": label, "pair_line": p.line, "config": name, "peer_method": m.name,
                       "source": p.source, "reference": p.reference}
                if id(p) not in readable:
                    row.update(status="error", note="cannot read the clouds")
                else:
                    o = peers.session.run(m, p)
                    n_src = peers.session.points[p.source]
                    used = o.source_points_used if o.source_points_used >= 0 else n_src
                    row.update(status=o.status, source_points=n_src,
                               reference_points=peers.session.points[p.reference],
                               translation_error_m=o.translation_error_m,
                               rotation_error_geodesic_deg=o.rotation_error_geodesic_deg,
                               rotation_error_euler_rad=o.rotation_error_euler_rad,
                               time_ms=o.time_ms, cpu_ms=o.cpu_ms,
                               iterations=o.iterations if o.iterations >= 0 else "",
                               converged="" if o.converged is None else int(o.converged),
                               points_processed=o.iterations * used if o.iterations >= 0 else "",
                               note=o.note)
                if row["status"] != "ok":
                    runner.failures.append((f"{what}: {label}:{p.line} {name}", f"{row['status']}: {row['note']}"))
                rows.append(row)
            log(f"  {time.perf_counter() - t0:.1f} s")
    return rows


def sevenscenes_pairs_files() -> list[str]:
    """The 7-Scenes Table I pairs files (one per offset), generated when missing."""
    files = []
    for offset, count in SEVEN_SETS:
        path = os.path.join(SEVEN_GENERATED, f"sevenscenes_table1_{offset}apart.txt")
        if not os.path.isfile(path):
            log(f"sevenscenes: generating {path} (bench/make_sevenscenes_pairs.py)")
            cmd = [sys.executable, os.path.join(REPO, "bench", "make_sevenscenes_pairs.py"), "--out",
                   SEVEN_GENERATED, "--offsets", str(offset), "--pairs-per-offset", str(count),
                   "--name", os.path.basename(path)]
            if subprocess.run(cmd, cwd=REPO).returncode != 0:
                raise RuntimeError(f"bench/make_sevenscenes_pairs.py failed for {path}")
        files.append(path)
    return files


def exp_sevenscenes(runner: Runner, wanted: list[str], exe: str, timeout_s: float) -> list[dict]:
    """Table I on the 7-Scenes sequence: our paper and default configurations, one seed per pair,
    and the peers of SEVEN_PEERS that are wanted and installed."""
    files = sevenscenes_pairs_files()
    rows = exp_table(runner, files, SEVEN_CONFIGS, 1, None, "sevenscenes")
    peers = Peers([w for w in SEVEN_PEERS if w in wanted], exe, timeout_s)
    for w, why in peers.not_run:
        log(f"sevenscenes: {PEER_NAME[w]} ({w}) not run: {why}")
    try:
        rows += exp_peers(runner, peers, files, None, "sevenscenes")
    finally:
        peers.close()
    return rows
