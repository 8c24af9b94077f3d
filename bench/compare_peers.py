#!/usr/bin/env python3
"""End-to-end speed and accuracy of sgd-icp against small_gicp, Open3D and PCL (issue 6).

usage: bench/compare_peers.py [PAIRS_FILE ...] [--reps 5] [--quick] [--out DIR] [options]

Runs every method on the same pairs (default: every ../shared/data/pairs/*.txt next to the
repository), alternating the methods pair by pair (the order rotates each time) for --reps
rounds, and writes per-run rows (runs.csv), a summary (summary.csv) and Markdown tables
(report.md) to --out. Progress goes to stderr, the report to stdout.

Timed region ("time"): building the search structure + normals/covariances (+ voxel downsampling
where used) + registration, from clouds already in the library's own container. File I/O and
the conversion of numpy arrays into a library's cloud type are excluded. sgd-icp is timed by
its own CLI (`sgdicp bench --csv`, column time_ms = KD-tree build + align()), one process per
registration. Every method starts from the identity; peers use a maximum correspondence
distance of 0.5 m and 30 iterations; sgd-icp runs with its defaults (d_max = 0.5 *scaled*
units, i.e. half the largest side of the joint bounding box, 60-100 m on KITTI) and, as
"sgdicp_dmax0.5m", with d_max = 0.5 m like the peers.

Errors against each pairs file's ground truth: translation error ||t - t_gt|| and geodesic
rotation error. A failing method/pair is recorded (status column), never fatal.

Budget (default ~12 min on a 2-core VM): a method slower than --slow-ms (1 s) on a pair in the
first round runs only --slow-reps (2) rounds there, slower than --very-slow-ms (5 s) only one;
PCL runs are stopped after --timeout (10 s). small_gicp's multi-threaded variants only with
--all-threads. See docs/performance.md for the results and how to read them.
"""
from __future__ import annotations

import argparse
import csv
import glob
import hashlib
import importlib
import math
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

# Single-threaded peers unless stated: OpenMP pools of Open3D honour OMP_NUM_THREADS, set before
# the import. small_gicp gets its thread count per call (an OpenMP num_threads clause overrides
# this), which is how its "all threads" variants use every core.
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CACHE = os.path.join(REPO, "bench", ".cache")


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# ----------------------------------------------------------------------------------------------
# Point-cloud readers (x y z as float32; non-finite points dropped, as sgdicp's readers do)
# ----------------------------------------------------------------------------------------------

def lzf_decompress(data: bytes, out_len: int) -> bytes:
    """LZF (liblzf) decompression, as used by PCD binary_compressed."""
    out = bytearray(out_len)
    ip = op = 0
    n = len(data)
    while ip < n:
        ctrl = data[ip]
        ip += 1
        if ctrl < 32:  # literal run of ctrl + 1 bytes
            ln = ctrl + 1
            out[op:op + ln] = data[ip:ip + ln]
            ip += ln
            op += ln
        else:  # back reference
            ln = ctrl >> 5
            ref = op - ((ctrl & 0x1F) << 8) - 1
            if ln == 7:
                ln += data[ip]
                ip += 1
            ref -= data[ip]
            ip += 1
            ln += 2
            if ref < 0:
                raise ValueError("corrupt LZF data")
            if ref + ln <= op:
                out[op:op + ln] = out[ref:ref + ln]
            else:  # overlapping copy
                for k in range(ln):
                    out[op + k] = out[ref + k]
            op += ln
    if op != out_len:
        raise ValueError(f"LZF: decompressed {op} bytes, expected {out_len}")
    return bytes(out)


_PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4",
              ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}


def read_pcd(path: str) -> np.ndarray:
    with open(path, "rb") as f:
        raw = f.read()
    header = {}
    pos = 0
    while True:
        end = raw.index(b"\n", pos)
        line = raw[pos:end].decode("ascii", "replace").strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, _, value = line.partition(" ")
        header[key.upper()] = value.split()
        if key.upper() == "DATA":
            break
    fields = header["FIELDS"]
    sizes = [int(s) for s in header["SIZE"]]
    types = header["TYPE"]
    counts = [int(c) for c in header.get("COUNT", ["1"] * len(fields))]
    npts = int(header["POINTS"][0]) if "POINTS" in header else int(header["WIDTH"][0]) * int(header["HEIGHT"][0])
    mode = header["DATA"][0].lower()
    cols = []  # (name, dtype, count)
    for name, size, typ, cnt in zip(fields, sizes, types, counts):
        cols.append((name, _PCD_TYPES[(typ.upper(), size)], cnt))
    if mode == "ascii":
        text = raw[pos:].decode("ascii", "replace").split()
        width = sum(c for _, _, c in cols)
        vals = np.array(text[: npts * width], dtype=np.float64).reshape(npts, width)
        offs, o = {}, 0
        for name, _, cnt in cols:
            offs[name] = o
            o += cnt
        xyz = vals[:, [offs["x"], offs["y"], offs["z"]]]
    elif mode == "binary":
        dt = np.dtype([(n, "<" + t, (c,)) if c > 1 else (n, "<" + t) for n, t, c in cols])
        arr = np.frombuffer(raw, dtype=dt, count=npts, offset=pos)
        xyz = np.stack([arr["x"], arr["y"], arr["z"]], axis=1)
    elif mode == "binary_compressed":
        csize, usize = np.frombuffer(raw, dtype="<u4", count=2, offset=pos)
        data = lzf_decompress(raw[pos + 8: pos + 8 + int(csize)], int(usize))
        # Structure of arrays: each field's values for all points, one field after the other.
        o = 0
        planes = {}
        for name, t, cnt in cols:
            nbytes = npts * cnt * np.dtype(t).itemsize
            planes[name] = np.frombuffer(data, dtype="<" + t, count=npts * cnt, offset=o)
            o += nbytes
        xyz = np.stack([planes["x"], planes["y"], planes["z"]], axis=1)
    else:
        raise ValueError(f"{path}: unsupported PCD DATA {mode}")
    return xyz


_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
              "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
              "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def read_ply(path: str) -> np.ndarray:
    with open(path, "rb") as f:
        raw = f.read()
    pos = 0
    fmt = None
    elements = []  # [name, count, [(prop, type)]]
    while True:
        end = raw.index(b"\n", pos)
        line = raw[pos:end].decode("ascii", "replace").strip()
        pos = end + 1
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "format":
            fmt = parts[1]
        elif parts[0] == "element":
            elements.append([parts[1], int(parts[2]), []])
        elif parts[0] == "property":
            if parts[1] == "list":
                elements[-1][2].append((parts[4], "list"))
            else:
                elements[-1][2].append((parts[2], _PLY_TYPES[parts[1]]))
        elif parts[0] == "end_header":
            break
    name, count, props = elements[0]
    if name != "vertex" or any(t == "list" for _, t in props):
        raise ValueError(f"{path}: expected a first 'vertex' element of scalar properties")
    names = [p for p, _ in props]
    ix, iy, iz = names.index("x"), names.index("y"), names.index("z")
    if fmt == "ascii":
        lines = raw[pos:].decode("ascii", "replace").splitlines()[:count]
        vals = np.array([ln.split()[: len(props)] for ln in lines], dtype=np.float64)
        return vals[:, [ix, iy, iz]]
    endian = "<" if fmt == "binary_little_endian" else ">"
    dt = np.dtype([(p, endian + t) for p, t in props])
    arr = np.frombuffer(raw, dtype=dt, count=count, offset=pos)
    return np.stack([arr["x"], arr["y"], arr["z"]], axis=1)


def read_text_xyz(path: str) -> np.ndarray:
    rows = []
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        for line in f:
            parts = [p for p in re.split(r"[\s,;]+", line.strip()) if p]
            if len(parts) < 3:
                continue
            try:
                rows.append((float(parts[0]), float(parts[1]), float(parts[2])))
            except ValueError:
                continue  # header line
    return np.array(rows, dtype=np.float64)


def read_vtk(path: str) -> np.ndarray:
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        tokens = f.read().split()
    i = next(k for k, t in enumerate(tokens) if t.upper() == "POINTS")
    n = int(tokens[i + 1])
    return np.array(tokens[i + 3: i + 3 + 3 * n], dtype=np.float64).reshape(n, 3)


def read_cloud_uncached(path: str) -> np.ndarray:
    ext = os.path.splitext(path)[1].lower()
    if ext == ".bin":
        xyz = np.fromfile(path, dtype="<f4").reshape(-1, 4)[:, :3]
    elif ext == ".f32":
        xyz = np.fromfile(path, dtype="<f4").reshape(-1, 3)
    elif ext == ".pcd":
        xyz = read_pcd(path)
    elif ext == ".ply":
        xyz = read_ply(path)
    elif ext in (".xyz", ".txt", ".csv"):
        xyz = read_text_xyz(path)
    elif ext == ".vtk":
        xyz = read_vtk(path)
    else:
        raise ValueError(f"{path}: unknown extension {ext}")
    xyz = np.asarray(xyz, dtype=np.float32)
    return np.ascontiguousarray(xyz[np.isfinite(xyz).all(axis=1)])


def cached_cloud(path: str) -> tuple[np.ndarray, str]:
    """The cloud as float32 (N, 3) and the path of its headerless .f32 copy in bench/.cache."""
    st = os.stat(path)
    key = hashlib.sha1(f"{os.path.abspath(path)}|{st.st_size}|{st.st_mtime_ns}".encode()).hexdigest()[:12]
    out = os.path.join(CACHE, "clouds", f"{os.path.basename(path)}.{key}.f32")
    if not os.path.exists(out):
        xyz = read_cloud_uncached(path)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        tmp = out + ".tmp"
        xyz.astype("<f4").tofile(tmp)
        os.replace(tmp, out)
    return np.fromfile(out, dtype="<f4").reshape(-1, 3), out


# ----------------------------------------------------------------------------------------------
# Pairs, errors
# ----------------------------------------------------------------------------------------------

@dataclass
class Pair:
    pairs_file: str  # stem, e.g. kitti_seq00
    line: int
    source: str
    reference: str
    T_gt: np.ndarray
    index: int = 0  # global index

    @property
    def label(self) -> str:
        return f"{self.pairs_file}:{self.line}"


def read_pairs(path: str) -> list[Pair]:
    out = []
    base = os.path.dirname(os.path.abspath(path))
    stem = os.path.splitext(os.path.basename(path))[0]
    with open(path, encoding="utf-8") as f:
        for lineno, line in enumerate(f, 1):
            s = line.strip()
            if not s or s.startswith("#"):
                continue
            parts = s.split()
            if len(parts) != 14:
                raise ValueError(f"{path}:{lineno}: expected 14 fields, got {len(parts)}")
            T = np.eye(4)
            T[:3, :] = np.array([float(v) for v in parts[2:]]).reshape(3, 4)
            out.append(Pair(stem, lineno, os.path.normpath(os.path.join(base, parts[0])),
                            os.path.normpath(os.path.join(base, parts[1])), T))
    return out


def translation_error(T: np.ndarray, T_gt: np.ndarray) -> float:
    return float(np.linalg.norm(T[:3, 3] - T_gt[:3, 3]))


def rotation_error_deg(T: np.ndarray, T_gt: np.ndarray) -> float:
    d = T[:3, :3].T @ T_gt[:3, :3]
    s = 0.5 * np.linalg.norm([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]])
    c = 0.5 * (np.trace(d) - 1.0)
    return math.degrees(math.atan2(s, c))


# ----------------------------------------------------------------------------------------------
# Methods
# ----------------------------------------------------------------------------------------------

@dataclass
class Outcome:
    T: np.ndarray | None = None
    time_ms: float = float("nan")
    cpu_ms: float = float("nan")  # process CPU time in the timed region (threads used ~ cpu/time)
    build_ms: float = float("nan")  # search-structure build alone, where known
    iterations: int = -1
    converged: bool | None = None
    peak_rss_mb: float = float("nan")
    status: str = "ok"
    note: str = ""


@dataclass
class Method:
    name: str
    family: str
    description: str
    threads: str
    run: object = None  # callable(pair, rep, ctx) -> Outcome
    available: bool = True
    why_not: str = ""
    needs_native: bool = True


@dataclass
class Context:
    args: argparse.Namespace
    clouds: dict = field(default_factory=dict)  # path -> (f32 array, f32 path)
    f64: dict = field(default_factory=dict)     # path -> float64 array
    pcl: object = None


def timed(fn):
    c0 = time.process_time()
    t0 = time.perf_counter()
    result = fn()
    t1 = time.perf_counter()
    c1 = time.process_time()
    return result, (t1 - t0) * 1e3, (c1 - c0) * 1e3


def run_sgdicp(extra: list[str]):
    def run(pair: Pair, rep: int, ctx: Context) -> Outcome:
        args = ctx.args
        with tempfile.TemporaryDirectory(prefix="sgdicp_cmp_") as tmp:
            pf = os.path.join(tmp, "pair.txt")
            with open(pf, "w") as f:
                gt = " ".join(f"{v:.17g}" for v in pair.T_gt[:3, :].reshape(-1))
                f.write(f"{pair.source} {pair.reference} {gt}\n")
            out_csv = os.path.join(tmp, "rows.csv")
            cmd = [args.sgdicp, "bench", pf, "--csv", out_csv, "--seed", str(2019 + rep)] + extra
            # Peak RSS through GNU time: a child forked from this (large) Python process would
            # report the parent's RSS as its own maximum.
            rss_file = os.path.join(tmp, "maxrss")
            if os.path.exists("/usr/bin/time"):
                cmd = ["/usr/bin/time", "-f", "%M", "-o", rss_file] + cmd
            with open(os.path.join(tmp, "stdout"), "w") as so, open(os.path.join(tmp, "stderr"), "w") as se:
                p = subprocess.run(cmd, stdout=so, stderr=se)
            peak = float("nan")
            try:
                with open(rss_file) as f:
                    peak = float(f.read().split()[-1]) / 1024.0
            except (OSError, ValueError, IndexError):
                pass
            if p.returncode != 0:
                with open(os.path.join(tmp, "stderr")) as f:
                    err = f.read().strip().replace("\n", " ")[:300]
                return Outcome(status="error", note=f"exit {p.returncode}: {err}")
            with open(out_csv, newline="") as f:
                row = next(csv.DictReader(f))
        # T is not in the CSV; the errors are, computed by the CLI with the same definitions.
        o = Outcome(time_ms=float(row["time_ms"]), build_ms=float(row["build_ms"]),
                    iterations=int(row["iterations"]), converged=row["converged"] == "1",
                    peak_rss_mb=peak)
        o.cpu_ms = float("nan")  # single-threaded by construction
        o.note = f"t_err={row['translation_error_m']};r_err={row['rotation_error_geodesic_deg']};stop={row['stop_reason']};n_src={row['source_points']}"
        return o
    return run


def small_gicp_run(reg: str, threads: int, voxel: bool):
    import small_gicp

    def run(pair: Pair, rep: int, ctx: Context) -> Outcome:
        a = ctx.args
        ref = ctx.f64[pair.reference]
        src = ctx.f64[pair.source]
        nt = threads
        res = a.voxel_for(pair.pairs_file) if voxel else None
        tgt_pc = small_gicp.PointCloud(ref)
        src_pc = small_gicp.PointCloud(src)

        def body():
            if voxel:
                if reg == "GICP":
                    # small_gicp's recommended pipeline (what small_gicp.align(numpy) does):
                    # downsample, KdTree, normals+covariances of 10 neighbours, for both clouds.
                    tgt, tree = small_gicp.preprocess_points(tgt_pc, downsampling_resolution=res,
                                                             num_neighbors=10, num_threads=nt)
                    s, _ = small_gicp.preprocess_points(src_pc, downsampling_resolution=res,
                                                        num_neighbors=10, num_threads=nt)
                else:  # point-to-point needs no covariances: downsample both, KdTree of the target
                    tgt = small_gicp.voxelgrid_sampling(tgt_pc, res, num_threads=nt)
                    s = small_gicp.voxelgrid_sampling(src_pc, res, num_threads=nt)
                    tree = small_gicp.KdTree(tgt, num_threads=nt)
            else:
                tgt, s = tgt_pc, src_pc
                tree = small_gicp.KdTree(tgt, num_threads=nt)
                if reg == "GICP":
                    small_gicp.estimate_covariances(tgt, tree, num_neighbors=10, num_threads=nt)
                    small_gicp.estimate_covariances(s, num_neighbors=10, num_threads=nt)
            r = small_gicp.align(tgt, s, tree, registration_type=reg,
                                 max_correspondence_distance=a.max_distance, num_threads=nt,
                                 max_iterations=a.max_iterations)
            return r, s.size()

        (r, n_src), ms, cpu = timed(body)
        return Outcome(T=np.array(r.T_target_source), time_ms=ms, cpu_ms=cpu,
                       iterations=int(r.iterations), converged=bool(r.converged),
                       note=f"src_points_used={n_src}" + (f";voxel={res}" if voxel else ""))
    return run


def small_gicp_kdtree_build(pair: Pair, rep: int, ctx: Context) -> Outcome:
    import small_gicp
    pc = small_gicp.PointCloud(ctx.f64[pair.reference])
    tree, ms, cpu = timed(lambda: small_gicp.KdTree(pc, num_threads=1))
    del tree
    return Outcome(time_ms=ms, cpu_ms=cpu, build_ms=ms)


def open3d_run(kind: str):
    import open3d as o3d
    reg = o3d.pipelines.registration

    def run(pair: Pair, rep: int, ctx: Context) -> Outcome:
        a = ctx.args
        tgt = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(ctx.f64[pair.reference]))
        src = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(ctx.f64[pair.source]))
        crit = reg.ICPConvergenceCriteria(max_iteration=a.max_iterations)

        def body():
            if kind == "point_to_plane":
                tgt.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=30))
                est = reg.TransformationEstimationPointToPlane()
            else:
                est = reg.TransformationEstimationPointToPoint()
            # registration_icp builds the target's KD-tree itself.
            return reg.registration_icp(src, tgt, a.max_distance, np.eye(4), est, crit)

        r, ms, cpu = timed(body)
        return Outcome(T=np.array(r.transformation), time_ms=ms, cpu_ms=cpu,
                       note=f"fitness={r.fitness:.4g}")
    return run


class PeerTimeout(RuntimeError):
    pass


class PclAdapter:
    """The C++ PCL peer as a child process; a run longer than `timeout` s kills and restarts it."""

    def __init__(self, exe: str, timeout: float):
        self.exe, self.timeout = exe, timeout
        self.start()

    def start(self):
        self.p = subprocess.Popen([self.exe], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                  stderr=subprocess.DEVNULL, text=True, bufsize=1)
        self.loaded: dict[str, str] = {}

    def ask(self, line: str, timeout: float | None = None) -> list[str]:
        import select
        self.p.stdin.write(line + "\n")
        self.p.stdin.flush()
        ready, _, _ = select.select([self.p.stdout], [], [], timeout or self.timeout)
        if not ready:
            self.p.kill()
            self.p.wait()
            self.start()
            raise PeerTimeout(f"no answer within {timeout or self.timeout:.0f} s (adapter restarted)")
        ans = self.p.stdout.readline()
        if not ans:
            self.start()
            raise RuntimeError("PCL adapter exited (restarted)")
        parts = ans.split()
        if parts[0] != "ok":
            raise RuntimeError(ans.strip())
        return parts[1:]

    def ensure(self, f32_path: str) -> str:
        if f32_path not in self.loaded:
            name = f"c{len(self.loaded)}"
            self.ask(f"load {name} {f32_path}", timeout=120)
            self.loaded[f32_path] = name
        return self.loaded[f32_path]

    def close(self):
        try:
            self.p.stdin.write("quit\n")
            self.p.stdin.flush()
            self.p.wait(timeout=10)
        except Exception:
            self.p.kill()


def pcl_run(method: str):
    def run(pair: Pair, rep: int, ctx: Context) -> Outcome:
        a = ctx.args
        s = ctx.pcl.ensure(ctx.clouds[pair.source][1])
        r = ctx.pcl.ensure(ctx.clouds[pair.reference][1])
        v = ctx.pcl.ask(f"run {method} {s} {r} {a.max_distance} {a.max_iterations}")
        T = np.array([float(x) for x in v[5:21]]).reshape(4, 4)
        return Outcome(T=T, time_ms=float(v[0]), cpu_ms=float(v[1]), iterations=int(v[2]),
                       converged=v[3] == "1", note=f"fitness={float(v[4]):.4g}")
    return run


def find_pcl_adapter(explicit: str | None) -> str | None:
    if explicit:
        return explicit if os.path.exists(explicit) else None
    for pattern in ("build-bench/bench/pcl_adapter/sgdicp_pcl_adapter", "build*/bench/pcl_adapter/sgdicp_pcl_adapter"):
        for c in sorted(glob.glob(os.path.join(REPO, pattern))):
            if os.access(c, os.X_OK):
                return c
    return None


def ensure_module(mod: str, pip_name: str, install: bool) -> tuple[bool, str]:
    try:
        importlib.import_module(mod)
        return True, ""
    except ImportError as e:
        if not install:
            return False, f"import {mod} failed ({e}); pip install {pip_name}"
    log(f"[setup] {mod} missing, running pip install {pip_name}")
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", pip_name], capture_output=True, text=True)
    if r.returncode != 0:
        return False, f"pip install {pip_name} failed: {r.stderr.strip()[-200:]}"
    try:
        importlib.invalidate_caches()
        importlib.import_module(mod)
        return True, ""
    except ImportError as e:  # e.g. Open3D needs libusb-1.0-0 from apt
        return False, f"import {mod} failed after install ({e})"


def build_methods(args) -> list[Method]:
    nt = args.threads
    ms: list[Method] = [
        Method("sgdicp", "sgd-icp", "sgd-icp defaults (CLI), d_max 0.5 scaled", "1",
               run_sgdicp([]), needs_native=False),
        Method("sgdicp_dmax0.5m", "sgd-icp", "sgd-icp defaults but d_max = 0.5 m", "1",
               run_sgdicp(["-d", str(args.max_distance), "--max-distance-unit", "m"]), needs_native=False),
    ]
    ok, why = (os.path.exists(args.sgdicp), f"{args.sgdicp} not found (scripts/build.sh)")
    for m in ms:
        m.available, m.why_not = ok, ("" if ok else why)

    ok, why = ensure_module("small_gicp", "small_gicp", args.install)
    for reg, label in (("ICP", "icp"), ("GICP", "gicp")):
        for voxel in (False, True):
            for threads in (1, nt):
                name = f"sg_{label}_{'vox' if voxel else 'full'}_{'1t' if threads == 1 else f'{threads}t'}"
                desc = f"small_gicp {reg}, {'voxel-downsampled' if voxel else 'full resolution'}, {threads} thread(s)"
                m = Method(name, "small_gicp", desc, str(threads))
                m.available, m.why_not = ok, why
                if ok:
                    m.run = small_gicp_run(reg, threads, voxel)
                ms.append(m)
    ok3, why3 = ensure_module("open3d", "open3d", args.install)
    for kind, name in (("point_to_point", "o3d_p2p_1t"), ("point_to_plane", "o3d_p2plane_1t")):
        m = Method(name, "open3d", f"Open3D ICP {kind.replace('_', '-')}" +
                   (" (normals of 30 neighbours, timed)" if kind == "point_to_plane" else ""), "1")
        m.available, m.why_not = ok3, why3
        if ok3:
            m.run = open3d_run(kind)
        ms.append(m)
    exe = find_pcl_adapter(args.pcl_adapter)
    for method, name, desc in (("icp", "pcl_icp_1t", "PCL IterativeClosestPoint (point-to-point)"),
                               ("icp_plane", "pcl_p2plane_1t", "PCL ICP with normals (point-to-plane; normals of 30 neighbours, timed)"),
                               ("gicp", "pcl_gicp_1t", "PCL GeneralizedIterativeClosestPoint")):
        m = Method(name, "pcl", desc, "1", pcl_run(method))
        m.available = exe is not None
        m.why_not = "" if exe else "PCL adapter not built (apt-get install libpcl-dev; cmake -DSGDICP_BUILD_BENCHMARKS=ON)"
        ms.append(m)
    ms.append(Method("sg_kdtree_build", "build-only", "small_gicp.KdTree(reference) build alone, 1 thread", "1",
                     small_gicp_kdtree_build if ok else None, ok, why))
    return ms


# ----------------------------------------------------------------------------------------------
# Main loop and reports
# ----------------------------------------------------------------------------------------------

DEFAULT_VOXEL = {  # metres; small_gicp's README value 0.25 m for outdoor LiDAR, scaled for small scenes
    "kitti_seq00": 0.25, "kitti_seq00_moved_copies": 0.25, "libpointmatcher_car": 0.25,
    "pcl_kinect_frames": 0.02, "eth_kinect_map_moved_copies": 0.02, "pcl_bunny": 0.002,
}

DEFAULT_METHODS = ("sgdicp,sgdicp_dmax0.5m,sg_icp_full_1t,sg_gicp_full_1t,sg_icp_vox_1t,sg_gicp_vox_1t,"
                   "o3d_p2p_1t,o3d_p2plane_1t,pcl_icp_1t,sg_kdtree_build")
ALL_THREADS_METHODS = ",sg_icp_full_{nt}t,sg_gicp_full_{nt}t,sg_icp_vox_{nt}t,sg_gicp_vox_{nt}t"
QUICK_METHODS = "sgdicp,sg_icp_full_1t,sg_gicp_vox_1t,o3d_p2p_1t,pcl_icp_1t,sg_kdtree_build"


def fmt(v, digits=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


def median(xs):
    xs = [x for x in xs if x is not None and math.isfinite(x)]
    return statistics.median(xs) if xs else float("nan")


def geomean(xs):
    xs = [x for x in xs if x is not None and math.isfinite(x) and x > 0]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def machine_info() -> str:
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except Exception:
        pass
    mem = "?"
    try:
        with open("/proc/meminfo") as f:
            mem = f"{int(next(l for l in f if l.startswith('MemTotal')).split()[1]) / 1048576:.1f} GiB"
    except Exception:
        pass
    return f"{platform.node()}: {os.cpu_count()} CPUs, {cpu}, {mem} RAM, Python {platform.python_version()}, load average {os.getloadavg()[0]:.2f} at the start"


def build_parser() -> argparse.ArgumentParser:
    """The command line; also the source of the peers' settings for eval/reproduce.py."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pairs", nargs="*", help="pairs files (default: ../shared/data/pairs/*.txt from the repository root)")
    ap.add_argument("--reps", type=int, default=None, help="rounds over all pairs and methods (default 5; --quick: 2)")
    ap.add_argument("--quick", action="store_true", help="first pair of each pairs file, 2 rounds, a few methods (~1-2 min)")
    ap.add_argument("--methods", default=None, help="comma-separated method names (see --list)")
    ap.add_argument("--list", action="store_true", help="list the methods and exit")
    ap.add_argument("--out", default=os.path.join(REPO, "results", "compare_peers"), help="output folder (default results/compare_peers)")
    ap.add_argument("--sgdicp", default=os.environ.get("SGDICP", os.path.join(REPO, "build", "sgdicp")), help="sgdicp CLI (default $SGDICP or build/sgdicp)")
    ap.add_argument("--pcl-adapter", default=None, help="sgdicp_pcl_adapter (default: build-bench/bench/pcl_adapter/ or any build*/)")
    ap.add_argument("--max-distance", type=float, default=0.5, help="peers' max correspondence distance, m (default 0.5)")
    ap.add_argument("--max-iterations", type=int, default=30, help="peers' iteration limit (default 30, Open3D's default)")
    ap.add_argument("--all-threads", action="store_true", help="also run small_gicp's multi-threaded variants (sg_*_Nt; not in the default: meaningful only on an idle machine)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1, help="threads of the multi-threaded small_gicp variants (default: all)")
    ap.add_argument("--voxel", action="append", default=[], metavar="PAIRS=METRES", help="voxel size for a pairs file stem (default: 0.25 m outdoor, 0.02 m Kinect, 0.002 m bunny)")
    ap.add_argument("--success", default="0.05,1", help="success threshold TRANS_M,ROT_DEG (default 0.05,1 as the README); 2,5 is also reported")
    ap.add_argument("--slow-ms", type=float, default=1000.0, help="a method slower than this on a pair in the first round ...")
    ap.add_argument("--slow-reps", type=int, default=2, help="... runs only this many rounds on that pair (default: 1000 ms, 2 rounds; keeps the default run near 15 min; the peers are deterministic, only their timing varies)")
    ap.add_argument("--very-slow-ms", type=float, default=5000.0, help="a method slower than this on a pair in the first round runs only that round on it (default 5000)")
    ap.add_argument("--timeout", type=float, default=10.0, help="PCL runs longer than this (s) are stopped, recorded as 'timeout' and not retried on that pair (default 10)")
    ap.add_argument("--max-pairs", type=int, default=0, help="use at most this many pairs per pairs file (0 = all)")
    ap.add_argument("--no-install", dest="install", action="store_false", help="do not pip install missing peers")
    return ap


def finish_args(args: argparse.Namespace) -> argparse.Namespace:
    """Derived settings the runners read: the voxel size per pairs file, an absolute CLI path."""
    voxel = dict(DEFAULT_VOXEL)
    for v in args.voxel:
        k, _, val = v.partition("=")
        voxel[k] = float(val)
    args.voxel_for = lambda stem: voxel.get(stem, 0.25)
    if not os.path.isabs(args.sgdicp):
        args.sgdicp = os.path.abspath(args.sgdicp)
    return args


def prepare(ctx: Context, pairs: list[Pair], active: list[Method]) -> list[Pair]:
    """Reads the clouds of `pairs` (cached), starts the PCL adapter if a PCL method is active and
    runs every native method once on the smallest pair (untimed warm-up). Returns the pairs whose
    clouds could be read."""
    log(f"[setup] reading {len({p.source for p in pairs} | {p.reference for p in pairs})} clouds (cached in bench/.cache/clouds)")
    for p in pairs:
        for path in (p.source, p.reference):
            if path not in ctx.clouds:
                try:
                    ctx.clouds[path] = cached_cloud(path)
                    ctx.f64[path] = ctx.clouds[path][0].astype(np.float64)
                except Exception as e:  # noqa: BLE001
                    log(f"[setup] cannot read {path}: {e}")
    pairs = [p for p in pairs if p.source in ctx.clouds and p.reference in ctx.clouds]
    if any(m.family == "pcl" for m in active) and ctx.pcl is None:
        ctx.pcl = PclAdapter(find_pcl_adapter(ctx.args.pcl_adapter), ctx.args.timeout)

    # Warm-up (untimed): first use of each library in this process on the smallest pair.
    smallest = min(pairs, key=lambda p: len(ctx.clouds[p.source][0]))
    for m in active:
        if m.needs_native:
            try:
                m.run(smallest, 0, ctx)
            except Exception as e:  # noqa: BLE001
                log(f"[warm-up] {m.name}: {e}")
    return pairs


def run_once(m: Method, p: Pair, rep: int, ctx: Context) -> tuple[Outcome, float, float]:
    """One registration of pair `p` by method `m`: its outcome (status "timeout", "error" or
    "non-finite" instead of an exception) and the translation [m] and geodesic rotation [deg]
    errors against the ground truth (nan when there is no result)."""
    try:
        o = m.run(p, rep, ctx)
    except PeerTimeout as e:
        o = Outcome(status="timeout", time_ms=ctx.args.timeout * 1e3, note=str(e))
    except Exception as e:  # noqa: BLE001
        o = Outcome(status="error", note=str(e).replace("\n", " ")[:300])
    t_err = r_err = float("nan")
    if o.T is not None:
        t_err = translation_error(o.T, p.T_gt)
        r_err = rotation_error_deg(o.T, p.T_gt)
        if not np.all(np.isfinite(o.T)):
            o.status = "non-finite"
    elif m.family == "sgd-icp" and o.status == "ok":
        kv = dict(x.split("=", 1) for x in o.note.split(";"))
        t_err, r_err = float(kv["t_err"]), float(kv["r_err"])
        if int(kv["n_src"]) != len(ctx.clouds[p.source][0]):
            log(f"[warn] {p.label}: sgdicp read {kv['n_src']} source points, compare_peers {len(ctx.clouds[p.source][0])}")
    return o, t_err, r_err


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)

    if args.quick:
        args.reps = args.reps or 2
        args.max_pairs = args.max_pairs or 1
        args.methods = args.methods or QUICK_METHODS
    args.reps = args.reps or 5
    finish_args(args)

    methods = build_methods(args)
    if args.list:
        for m in methods:
            print(f"{m.name:20s} {m.description}" + ("" if m.available else f"  [unavailable: {m.why_not}]"))
        return 0
    default = DEFAULT_METHODS + (ALL_THREADS_METHODS if args.all_threads else "")
    wanted = (args.methods or default).format(nt=args.threads).split(",")
    by_name = {m.name: m for m in methods}
    unknown = [w for w in wanted if w not in by_name]
    if unknown:
        log(f"unknown methods: {unknown} (see --list)")
        return 2
    methods = [by_name[w] for w in dict.fromkeys(wanted)]
    for m in methods:
        if not m.available:
            log(f"[setup] skipping {m.name}: {m.why_not}")
    active = [m for m in methods if m.available]

    pairs_files = args.pairs or sorted(glob.glob(os.path.join(REPO, "..", "shared", "data", "pairs", "*.txt")))
    if not pairs_files:
        log("no pairs files (expected ../shared/data/pairs/*.txt next to the repository)")
        return 2
    pairs: list[Pair] = []
    for pf in pairs_files:
        ps = read_pairs(pf)
        if args.max_pairs:
            ps = ps[: args.max_pairs]
        pairs += ps
    for i, p in enumerate(pairs):
        p.index = i

    ctx = Context(args)
    log(f"[setup] {machine_info()}")
    pairs = prepare(ctx, pairs, active)

    rows = []
    slow: dict[int, set] = {}  # pair index -> methods slower than --slow-ms in the first round
    timed_out: dict[int, set] = {}  # pair index -> methods that exceeded --timeout
    very_slow: dict[int, set] = {}  # pair index -> methods slower than --very-slow-ms in the first round
    os.makedirs(args.out, exist_ok=True)
    live = open(os.path.join(args.out, "runs.partial.csv"), "w", newline="")
    live_writer = None
    total = args.reps * len(pairs) * len(active)
    done = 0
    t_start = time.time()
    for rep in range(args.reps):
        for p in pairs:
            k = (rep * len(pairs) + p.index) % len(active)
            order = active[k:] + active[:k]  # rotate so no method always runs first
            for m in order:
                if m.name in timed_out.get(p.index, set()):
                    continue  # timed out once on this pair: not retried
                if rep >= 1 and m.name in very_slow.get(p.index, set()):
                    continue  # one round of a very slow method is enough
                if rep >= args.slow_reps and m.name in slow.get(p.index, set()):
                    continue  # a slow method: --slow-reps rounds are enough for its median
                o, t_err, r_err = run_once(m, p, rep, ctx)
                if o.status == "timeout":
                    slow.setdefault(p.index, set()).add(m.name)
                    timed_out.setdefault(p.index, set()).add(m.name)
                rows.append(dict(pairs_file=p.pairs_file, line=p.line, source=os.path.basename(p.source),
                                 reference=os.path.basename(p.reference), source_points=len(ctx.clouds[p.source][0]),
                                 reference_points=len(ctx.clouds[p.reference][0]), method=m.name, family=m.family,
                                 threads=m.threads, rep=rep, status=o.status, time_ms=o.time_ms, cpu_ms=o.cpu_ms,
                                 build_ms=o.build_ms, translation_error_m=t_err, rotation_error_deg=r_err,
                                 iterations=o.iterations, converged=o.converged, peak_rss_mb=o.peak_rss_mb, note=o.note))
                done += 1
                if live_writer is None:
                    live_writer = csv.DictWriter(live, fieldnames=list(rows[-1].keys()))
                    live_writer.writeheader()
                live_writer.writerow(rows[-1])
                live.flush()
                if rep == 0 and o.status == "ok" and o.time_ms > args.slow_ms:
                    slow.setdefault(p.index, set()).add(m.name)
                if rep == 0 and o.status == "ok" and o.time_ms > args.very_slow_ms:
                    very_slow.setdefault(p.index, set()).add(m.name)
            el = time.time() - t_start
            log(f"[run] round {rep + 1}/{args.reps} {p.label:34s} {done}/{total} runs (at most), {el:.0f} s elapsed")
    if ctx.pcl:
        ctx.pcl.close()
    live.close()
    os.replace(os.path.join(args.out, "runs.partial.csv"), os.path.join(args.out, "runs.csv"))

    report = make_report(rows, active, pairs, args, time.time() - t_start)
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(report)
    print(report)
    log(f"[done] {args.out}/runs.csv, summary.csv, report.md")
    return 0


def make_report(rows, methods, pairs, args, elapsed) -> str:
    succ_t, succ_r = (float(x) for x in args.success.split(","))
    reg_methods = [m for m in methods if m.family != "build-only"]
    # Per (method, pair): median time, errors over the rounds.
    per = {}
    for r in rows:
        per.setdefault((r["method"], r["pairs_file"], r["line"]), []).append(r)
    pair_keys = [(p.pairs_file, p.line) for p in pairs]

    def timed_rows(rs):  # a timeout counts with the timeout as its time (a lower bound)
        return [r for r in rs if r["status"] in ("ok", "timeout")]

    def med_time(m, key):
        return median([r["time_ms"] for r in timed_rows(per.get((m, *key), []))])

    def ok(r, t=succ_t, d=succ_r):
        return r["status"] == "ok" and r["translation_error_m"] < t and r["rotation_error_deg"] < d

    groups = sorted({p.pairs_file for p in pairs})
    lines = []
    out = lines.append
    out("# sgd-icp vs peers: end-to-end registration\n")
    out(f"{machine_info()}; {args.reps} rounds, methods alternated per pair; wall time of this run {elapsed / 60:.1f} min.\n")
    out("Time = search-structure build + normals/covariances (+ voxel downsampling where used) + registration; "
        "file I/O excluded. Identity start. Peers: max correspondence distance "
        f"{args.max_distance} m, at most {args.max_iterations} iterations. sgd-icp: its defaults "
        "(d_max 0.5 *scaled* = half the scene's largest side), and `sgdicp_dmax0.5m` with d_max = 0.5 m.\n")
    out(f"Ratio = method time / sgd-icp time on the same pair (medians over rounds), then the median over the pairs: "
        f"> 1 means sgd-icp is faster. Success: translation < {succ_t} m and rotation < {succ_r} deg (and < 2 m, 5 deg). "
        "cpu/time ~ threads actually used (process CPU time / wall time; below 1 for one thread means the machine was busy). "
        f"A method slower than {args.slow_ms:.0f} ms on a pair in the first round runs {args.slow_reps} rounds on it, slower than "
        f"{args.very_slow_ms:.0f} ms only 1 (column runs); PCL runs are stopped after {args.timeout:.0f} s.\n")
    summary_rows = []
    for g in groups + ["ALL"]:
        keys = [k for k in pair_keys if g == "ALL" or k[0] == g]
        if not keys:
            continue
        n_src = median([len_ for len_ in (r["source_points"] for r in rows if (r["pairs_file"], r["line"]) in keys)])
        out(f"\n## {g} ({len(keys)} pairs, ~{n_src:.0f} source points)\n" if g != "ALL" else f"\n## All pairs ({len(keys)})\n")
        out("| method | threads | runs | success | success 2 m/5° | median t err [m] | median r err [°] | median time [ms] | ratio vs sgdicp (median over pairs) | ratio geo-mean | cpu/time | median iters |")
        out("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for m in reg_methods + [m for m in methods if m.family == "build-only"]:
            rs = [r for k in keys for r in per.get((m.name, *k), [])]
            if not rs:
                continue
            good = [r for r in rs if r["status"] == "ok"]
            ratios = []
            for k in keys:
                a, b = med_time(m.name, k), med_time("sgdicp", k)
                if m.family == "build-only":
                    b = median([r["build_ms"] for r in per.get(("sgdicp", *k), []) if r["status"] == "ok"])
                if math.isfinite(a) and math.isfinite(b) and b > 0:
                    ratios.append(a / b)
            cpu = [r["cpu_ms"] / r["time_ms"] for r in good if math.isfinite(r["cpu_ms"]) and r["time_ms"] > 0]
            s1 = sum(ok(r) for r in rs) / len(rs)
            s2 = sum(ok(r, 2.0, 5.0) for r in rs) / len(rs)
            errs = sum(r["status"] not in ("ok", "timeout") for r in rs)
            touts = sum(r["status"] == "timeout" for r in rs)
            label = m.name + (f" ({errs} failed)" if errs else "") + (f" ({touts} timed out, counted as {args.timeout:.0f} s)" if touts else "")
            if m.family == "build-only":
                out(f"| {label} (vs sgdicp build_ms) | {m.threads} | {len(rs)} | – | – | – | – | {fmt(median([r['time_ms'] for r in good]))} | {fmt(median(ratios))} | {fmt(geomean(ratios))} | {fmt(median(cpu), 2)} | – |")
                continue
            out(f"| {label} | {m.threads} | {len(rs)} | {100 * s1:.0f} % | {100 * s2:.0f} % | "
                f"{fmt(median([r['translation_error_m'] for r in good]))} | {fmt(median([r['rotation_error_deg'] for r in good]))} | "
                f"{fmt(median([r['time_ms'] for r in timed_rows(rs)]))} | {fmt(median(ratios))} | {fmt(geomean(ratios))} | "
                f"{fmt(median(cpu), 2)} | {fmt(median([float(r['iterations']) for r in good if r['iterations'] >= 0]))} |")
            summary_rows.append(dict(group=g, method=m.name, threads=m.threads, runs=len(rs), failed=errs,
                                     success=s1, success_2m5deg=s2,
                                     median_t_err_m=median([r["translation_error_m"] for r in good]),
                                     median_r_err_deg=median([r["rotation_error_deg"] for r in good]),
                                     median_time_ms=median([r["time_ms"] for r in timed_rows(rs)]), timeouts=touts,
                                     ratio_median=median(ratios), ratio_geomean=geomean(ratios)))
        if g == "ALL":
            continue
    # sgd-icp build share
    build = [r["build_ms"] / r["time_ms"] for r in rows if r["method"] == "sgdicp" and r["status"] == "ok" and r["time_ms"] > 0]
    if build:
        out(f"\nsgd-icp: KD-tree build = {100 * median(build):.0f} % of its time (median over runs); "
            f"peak RSS of the CLI process (file reading included): median {fmt(median([r['peak_rss_mb'] for r in rows if r['method'] == 'sgdicp']))} MB, "
            f"max {fmt(max([r['peak_rss_mb'] for r in rows if r['method'] == 'sgdicp' and math.isfinite(r['peak_rss_mb'])], default=float('nan')))} MB.\n")
    # Per-pair table
    out("\n## Per pair: median time [ms] (ratio vs sgdicp)\n")
    names = [m.name for m in methods]
    out("| pair | " + " | ".join(names) + " |")
    out("| --- | " + " | ".join("---:" for _ in names) + " |")
    for k in pair_keys:
        base = med_time("sgdicp", k)
        base_build = median([r["build_ms"] for r in per.get(("sgdicp", *k), []) if r["status"] == "ok"])
        cells = []
        for m in methods:
            t = med_time(m.name, k)
            b = base_build if m.family == "build-only" else base
            cells.append(f"{fmt(t)} ({fmt(t / b, 2)})" if math.isfinite(t) and math.isfinite(b) and b > 0 else fmt(t))
        src = next((r["source"] for r in rows if (r["pairs_file"], r["line"]) == k), "")
        out(f"| {k[0]}:{k[1]} {src} | " + " | ".join(cells) + " |")
    failures = [r for r in rows if r["status"] != "ok"]
    if failures:
        out("\n## Failed runs\n")
        for r in failures[:50]:
            out(f"- {r['method']} {r['pairs_file']}:{r['line']} round {r['rep']}: {r['status']} {r['note']}")
    with open(os.path.join(args.out, "summary.csv"), "w", newline="") as f:
        if summary_rows:
            w = csv.DictWriter(f, fieldnames=list(summary_rows[0].keys()))
            w.writeheader()
            w.writerows(summary_rows)
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
