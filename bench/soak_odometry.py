#!/usr/bin/env python3
"""Soak test of the odometry: RSS, frame time, map size and lost frames per block of a long run.

A long, continuous run back and forth along a real sequence, reported per block of frames
(default 1,000).

    python3 bench/soak_odometry.py --sequence handheld --frames 2000 --check
    python3 bench/soak_odometry.py --sequence sevenscenes --frames 10000 --json soak.json
    python3 bench/soak_odometry.py --sequence handheld --python

Sequences (from --data, default ../shared/data beside the repository), played back and forth
without a break: frames 0..n-1, then n-2..1, then 0..n-1 again, ... (no frame twice in a row at a
turn, so every frame is a motion; frame k is order[k % len(order)] of `back_and_forth`):
- handheld: the 77 scans of balm_handheld_lidar/scans (a hand-held spinning LiDAR, 2 Hz);
- sevenscenes: the 600 depth frames of sevenscenes_redkitchen (a Kinect, 30 Hz; 59 of them are
  byte-identical to the frame before, which the odometry gives the previous pose).
The played sequence is a folder of symlinks in --out (`%06d.bin`, or `frame-%06d.depth.png` with
camera-intrinsics.txt, which the CLI reads as a 7-Scenes folder: its summary's layout is checked).

The CLI (default) runs `sgdicp odometry FOLDER --poses-out P --report R -q`, whose report gets one
line per frame as the run goes; its resident memory (VmRSS, /proc/PID/status) and the frames done
are polled every POLL_S seconds, and a block's RSS is the first sample at or after its last frame
(the run's last sample for the last block); the peak is the larger of the samples and the child's
ru_maxrss. --python runs sgd_icp.Odometry() (default settings) in this process on frames read with
read_points / read_depth_image (the CLI's depth settings), RSS from /proc/self/status after each
block. Per-frame time is the report's time_ms (the odometry's own, reading excluded); a block's map
points are the report's map_points (the map a frame was registered to) of its last registered
frame; lost frames are the report's failed ones. Wall time is the whole run, reading included.

--check exits 1, naming each failed target, unless every frame was registered, RSS grew less than
MAX_RSS_GROWTH_MB from the end of block 1 to the end, the last block's median time is at most
MAX_TIME_RATIO x the reference block's (block 2; block 1 when there are only two blocks: a
block 2 compared with itself would prove nothing), and the map at the end holds at most
MAX_MAP_RATIO x its points at the end of block 1. It needs two blocks at least. A run that stops
early (a crash, an error) always exits 1. Needs Linux (/proc); the CLI mode needs no package.

RSS is what the process holds, with what glibc's malloc keeps after a free (its dynamic mmap
threshold moves the frames' large buffers into the heap): here 1.2-2.4x the live memory, and it
depends on the order of allocations (the same 1,000 7-Scenes frames, with and without --report:
102 and 142 MB). `sgdicp odometry` fixes the threshold at 128 kB itself (apps/odometry.cpp), and
its RSS follows the live memory (the map's ~70 bytes a point); --python runs with Python's
allocator settings, as a user's process would.
--python also reports the heap in use (glibc's mallinfo2) at each block's end: the live memory,
which a leak would grow, without the allocator's own keeping.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

REPO = Path(__file__).resolve().parent.parent

# After block 1 memory grows only with the map's filling (handheld, frames 1001-2000: +8 MB).
MAX_RSS_GROWTH_MB = 20.0
# Time must not grow with the frame count; 30 % is room for a shared 2-core CI machine's noise.
MAX_TIME_RATIO = 1.3
# The map is bounded by the space the path covers; later passes fill its voxels (handheld: 1.07x).
MAX_MAP_RATIO = 1.10
POLL_S = 0.2  # seconds between two samples of the CLI's RSS and frame count

SEQUENCES = {  # name: (folder under --data, frame glob, link name, 7-Scenes intrinsics or None)
    "handheld": ("balm_handheld_lidar/scans", "*.bin", "{:06d}.bin", None),
    "sevenscenes": ("sevenscenes_redkitchen", "frame-*.depth.png", "frame-{:06d}.depth.png",
                    "camera-intrinsics.txt"),
}
EXPECTED_LAYOUT = {"handheld": "clouds", "sevenscenes": "7scenes"}  # the CLI summary's `layout:`
# The CLI's depth settings for a 7-Scenes folder (DepthImageSettings' defaults, apps/cli_common.cpp;
# depth scale 0 = the data's own, 1000 per metre there). read_depth_image's defaults are the same
# today; given explicitly so that the two modes read the same points if either changes.
CLI_DEPTH = {"depth_scale": 0.0, "max_depth": 10.0, "min_depth": 0.0, "pixel_stride": 1,
             "border": 0}


@dataclass
class Frame:
    """What a soak needs of one frame's report."""
    failed: bool
    time_ms: float
    map_points: int


@dataclass
class Run:
    frames: list[Frame]
    rss_mb: list[float]  # at the end of each block reached
    peak_rss_mb: float
    wall_s: float
    layout: str = ""
    error: str = ""  # why the run went wrong (stopped early, another layout), empty when it did not
    samples: list[tuple[int, float]] = field(default_factory=list)  # (frames done, RSS MB)
    heap_mb: list[float] = field(default_factory=list)  # --python: malloc's bytes in use per block


@dataclass
class Block:
    first: int  # frame numbers from 1, inclusive
    last: int
    rss_mb: float
    median_ms: float
    p95_ms: float
    map_points: int
    lost: int


def back_and_forth(n: int) -> list[int]:
    """One period of the path over n frames: 0..n-1, then n-2..1 (the next period starts at 0)."""
    return list(range(n)) + list(range(n - 2, 0, -1))


def played(n: int, frames: int) -> list[int]:
    """The source frame of each of `frames` played frames."""
    order = back_and_forth(n)
    return [order[k % len(order)] for k in range(frames)]


def block_ends(frames: int, block: int) -> list[int]:
    """Frames done at the end of each block (the last block may be shorter)."""
    return [min(end, frames) for end in range(block, frames + block, block)]


def percentile(values: list[float], q: float) -> float:
    """The q-th percentile with linear interpolation (numpy.percentile's default)."""
    s = sorted(values)
    pos = (len(s) - 1) * q / 100.0
    lo = math.floor(pos)
    hi = min(lo + 1, len(s) - 1)
    return s[lo] + (s[hi] - s[lo]) * (pos - lo)


def make_blocks(frames: list[Frame], rss_mb: list[float], block: int) -> list[Block]:
    """One Block per block of frames done; rss_mb[i] is the RSS at the end of block i."""
    out = []
    for i, end in enumerate(block_ends(len(frames), block)):
        first = i * block
        chunk = frames[first:end]
        registered = [f for f in frames[:end] if not f.failed]
        times = [f.time_ms for f in chunk]
        out.append(Block(first + 1, end, rss_mb[i] if i < len(rss_mb) else math.nan,
                         percentile(times, 50), percentile(times, 95),
                         registered[-1].map_points if registered else 0,
                         sum(f.failed for f in chunk)))
    return out


def time_reference(blocks: list[Block]) -> int:
    """The block the last one's median time is compared with: block 2 (block 1 fills the map), or
    block 1 when there are two blocks only (block 2 is then the last one)."""
    return 1 if len(blocks) >= 3 else 0


def totals(blocks: list[Block], run: Run) -> dict[str, float]:
    ref = blocks[time_reference(blocks)]
    return {
        "frames": len(run.frames),
        "lost": sum(b.lost for b in blocks),
        "peak_rss_mb": run.peak_rss_mb,
        "wall_s": run.wall_s,
        "rss_growth_mb": blocks[-1].rss_mb - blocks[0].rss_mb,
        "time_ratio": blocks[-1].median_ms / ref.median_ms if ref.median_ms > 0 else math.inf,
        "time_reference_block": time_reference(blocks) + 1,
        "map_ratio": (blocks[-1].map_points / blocks[0].map_points if blocks[0].map_points
                      else math.inf),
    }


def check(total: dict[str, float], frames: int, run: Run) -> list[str]:
    """The targets missed, one line each; empty when all are met."""
    failures = []
    if run.error:
        failures.append(run.error)
    if total["frames"] < frames:
        failures.append(f"the run did {total['frames']} of {frames} frames")
    if total["lost"]:
        failures.append(f"{total['lost']} frames lost (every frame must register)")
    if not total["rss_growth_mb"] < MAX_RSS_GROWTH_MB:  # NaN (no sample) fails too
        failures.append(f"RSS grew {total['rss_growth_mb']:.1f} MB after block 1 "
                        f"(limit {MAX_RSS_GROWTH_MB:g} MB)")
    if not total["time_ratio"] <= MAX_TIME_RATIO:
        failures.append(f"median frame time of the last block is {total['time_ratio']:.2f}x block "
                        f"{total['time_reference_block']}'s (limit {MAX_TIME_RATIO:g}x)")
    if not total["map_ratio"] <= MAX_MAP_RATIO:
        failures.append(f"the map grew to {total['map_ratio']:.3f}x its points at the end of "
                        f"block 1 (limit {MAX_MAP_RATIO:g}x)")
    return failures


def link_frames(sequence: str, data: Path, out: Path, frames: int) -> Path:
    """A fresh folder of symlinks out/<sequence>-frames, in name order the played frames."""
    sub, pattern, name, intrinsics = SEQUENCES[sequence]
    source = sorted((data / sub).resolve().glob(pattern))
    if len(source) < 2:
        raise SystemExit(f"{data / sub}: fewer than 2 frames ({pattern})")
    folder = out / f"{sequence}-frames"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    for k, i in enumerate(played(len(source), frames)):
        (folder / name.format(k)).symlink_to(source[i])
    if intrinsics:
        (folder / intrinsics).symlink_to((data / sub / intrinsics).resolve())
    return folder


def mb(kib: float) -> float:
    """Megabytes (10^6 bytes) of a /proc or getrusage figure in kB (1024 bytes)."""
    return kib * 1024 / 1e6


def proc_status_kb(pid: int | str) -> dict[str, int]:
    """VmRSS and VmHWM of a process in kB; empty when it is gone (or a zombie)."""
    try:
        text = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return {}
    return {line.split(":")[0]: int(line.split()[1]) for line in text.splitlines()
            if line.startswith(("VmRSS:", "VmHWM:"))}


def rss_at(samples: list[tuple[int, float]], ends: list[int]) -> list[float]:
    """For each block end, the RSS of the first (frames done, RSS) sample at or after it, else of
    the last sample (the process ended before another was taken)."""
    out = []
    for end in ends:
        later = [rss for done, rss in samples if done >= end]
        out.append(later[0] if later else samples[-1][1] if samples else math.nan)
    return out


def report_frames(path: Path) -> list[Frame]:
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return [Frame(row["failed"] == "1", float(row["time_ms"]), int(row["map_points"]))
                for row in csv.DictReader(f)]


def progress(sequence: str, done: int, frames: int, rss_mb: float, start: float) -> None:
    print(f"{sequence}: {done}/{frames} frames, RSS {rss_mb:.1f} MB, "
          f"{time.monotonic() - start:.0f} s", file=sys.stderr, flush=True)


class LineCounter:
    """Lines in a file being appended to, read incrementally (the file may not exist yet)."""

    def __init__(self, path: Path):
        self.path, self.file, self.lines = path, None, 0

    def count(self) -> int:
        if self.file is None and self.path.exists():
            self.file = open(self.path, "rb")
        if self.file is not None:
            self.lines += self.file.read().count(b"\n")
        return self.lines

    def close(self) -> None:
        if self.file is not None:
            self.file.close()


def poll(child: subprocess.Popen, report: Path, sequence: str, frames: int, block: int
         ) -> tuple[list[tuple[int, float]], float]:
    """Samples (frames done, RSS MB) of the child every POLL_S s until it exits; its peak RSS."""
    counter, ends, samples, peak_kb = LineCounter(report), block_ends(frames, block), [], 0
    start = time.monotonic()
    while True:
        done = max(counter.count() - 1, 0)  # the frames before the RSS is read: the header is 1
        status = proc_status_kb(child.pid)
        if "VmRSS" in status:
            samples.append((done, mb(status["VmRSS"])))
            peak_kb = max(peak_kb, status["VmHWM"])
            if ends and done >= ends[0]:
                progress(sequence, done, frames, samples[-1][1], start)
                ends = [e for e in ends if e > done]
        pid, wait_status, usage = os.wait4(child.pid, os.WNOHANG)
        if pid:
            child.returncode = os.waitstatus_to_exitcode(wait_status)
            counter.close()
            return samples, mb(max(peak_kb, usage.ru_maxrss))  # ru_maxrss: kB on Linux
        time.sleep(POLL_S)


def run_cli(binary: Path, folder: Path, work: Path, sequence: str, frames: int, block: int) -> Run:
    work.mkdir(parents=True, exist_ok=True)
    report = work / "report.csv"
    report.unlink(missing_ok=True)
    cmd = [str(binary), "odometry", str(folder), "--poses-out", str(work / "poses.txt"),
           "--report", str(report), "-q"]
    start = time.monotonic()
    with open(work / "stdout.txt", "w") as out, open(work / "stderr.txt", "w") as err:
        child = subprocess.Popen(cmd, stdout=out, stderr=err)
        samples, peak_mb = poll(child, report, sequence, frames, block)
    wall = time.monotonic() - start
    done = report_frames(report)
    layout = re.search(r"\blayout: ([\w-]+)", (work / "stdout.txt").read_text())
    layout = layout.group(1) if layout else ""
    error = ""
    if child.returncode != 0:
        tail = (work / "stderr.txt").read_text().strip().splitlines()[-3:]
        error = f"exit status {child.returncode}: " + " / ".join(tail)
    elif layout != EXPECTED_LAYOUT[sequence]:
        error = f"the CLI read {folder} as layout '{layout}', not '{EXPECTED_LAYOUT[sequence]}'"
    return Run(done, rss_at(samples, block_ends(len(done), block)), peak_mb, wall, layout, error,
               samples)


def frame_reader(sequence: str, folder: Path) -> Callable[[Path], object]:
    import sgd_icp

    if SEQUENCES[sequence][3] is None:
        return sgd_icp.read_points
    intrinsics = folder / SEQUENCES[sequence][3]
    return lambda path: sgd_icp.read_depth_image(path, intrinsics, **CLI_DEPTH)


def heap_in_use_mb() -> float:
    """The bytes glibc's malloc has handed out and not had back (mallinfo2's uordblks + hblkhd):
    the live memory, without what the allocator keeps after a free; NaN without glibc 2.33+."""
    import ctypes

    class MallInfo2(ctypes.Structure):
        _fields_ = [(name, ctypes.c_size_t) for name in (
            "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
            "fordblks", "keepcost")]

    try:
        mallinfo2 = ctypes.CDLL(None).mallinfo2
    except (OSError, AttributeError):
        return math.nan
    mallinfo2.restype = MallInfo2
    info = mallinfo2()
    return (info.uordblks + info.hblkhd) / 2**20


def run_python(folder: Path, sequence: str, frames: int, block: int) -> Run:
    import sgd_icp

    read = frame_reader(sequence, folder)
    files = sorted(folder.glob(SEQUENCES[sequence][1]))[:frames]
    ends, out, rss, samples, heap = set(block_ends(frames, block)), [], [], [], []
    start = time.monotonic()
    odometry = sgd_icp.Odometry()
    for k, path in enumerate(files):
        try:
            points = read(path)
        except (OSError, ValueError) as e:  # as the CLI: an unreadable frame is a lost frame
            odometry.skip_frame(f"unreadable: {e}")
        else:
            odometry.register_frame(points)
        r = odometry.last_report
        out.append(Frame(bool(r.failed), float(r.time_ms), int(r.map_points)))
        if k + 1 in ends:
            rss.append(mb(proc_status_kb("self")["VmRSS"]))
            samples.append((k + 1, rss[-1]))
            heap.append(heap_in_use_mb())
            progress(sequence, k + 1, frames, rss[-1], start)
    wall = time.monotonic() - start
    return Run(out, rss, mb(proc_status_kb("self")["VmHWM"]), wall, EXPECTED_LAYOUT[sequence],
               samples=samples, heap_mb=heap)


def print_table(blocks: list[Block], total: dict[str, float]) -> None:
    print("| frames | RSS at end (MB) | time median (ms) | time p95 (ms) | map points at end "
          "| lost |")
    print("|---|---|---|---|---|---|")
    for b in blocks:
        print(f"| {b.first}-{b.last} | {b.rss_mb:.1f} | {b.median_ms:.1f} | {b.p95_ms:.1f} | "
              f"{b.map_points} | {b.lost} |")
    print(f"\ntotal: {total['frames']} frames, {total['lost']} lost, peak RSS "
          f"{total['peak_rss_mb']:.1f} MB, wall {total['wall_s']:.1f} s, RSS growth after block 1 "
          f"{total['rss_growth_mb']:+.1f} MB, median time last block / block "
          f"{total['time_reference_block']} {total['time_ratio']:.2f}x, map points end / block 1 "
          f"{total['map_ratio']:.3f}x")


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sequence", required=True, choices=sorted(SEQUENCES),
                        help="the sequence played back and forth: handheld (77 LiDAR scans) or "
                        "sevenscenes (600 Kinect depth frames) [required]")
    parser.add_argument("--frames", type=int, default=10000,
                        help="frames to run, a count [default: 10000]")
    parser.add_argument("--block", type=int, default=1000,
                        help="frames per reported block, a count [default: 1000]")
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data",
                        help="the shared data folder [default: ../shared/data beside the "
                        "repository]")
    parser.add_argument("--sgdicp", type=Path, default=REPO / "build" / "sgdicp",
                        help="the sgdicp executable of the CLI mode [default: build/sgdicp]")
    parser.add_argument("--python", action="store_true",
                        help="run sgd_icp.Odometry() in this process instead of the CLI "
                        "[default: the CLI]")
    parser.add_argument("--out", type=Path, default=REPO / "build" / "soak",
                        help="folder of the frame links, the CLI's poses, report and output "
                        "[default: build/soak]")
    parser.add_argument("--check", action="store_true",
                        help="exit 1 unless every frame registered and RSS, frame time and map "
                        "points stayed within the script's MAX_* limits [default: no check]")
    parser.add_argument("--json", type=Path, help="also write the blocks, totals and check here "
                        "[default: none]")
    args = parser.parse_args()
    if args.frames < 1 or args.block < 1 or args.frames >= 1_000_000:
        parser.error("--frames must be in [1, 999999] and --block at least 1")
    if args.check and args.frames <= args.block:
        parser.error("--check needs two blocks at least (--frames > --block): a growth is "
                     "measured from the end of block 1")
    return args


def main() -> int:
    args = parse_args()
    folder = link_frames(args.sequence, args.data, args.out, args.frames)
    if args.python:
        run = run_python(folder, args.sequence, args.frames, args.block)
    else:
        run = run_cli(args.sgdicp, folder, args.out / f"{args.sequence}-cli", args.sequence,
                      args.frames, args.block)
    mode = "python" if args.python else f"cli {args.sgdicp}"
    print(f"{args.sequence} ({mode}, layout {run.layout}): {len(run.frames)} of {args.frames} "
          "frames")
    if not run.frames:
        print(f"no frame done: {run.error}")
        return 1
    blocks = make_blocks(run.frames, run.rss_mb, args.block)
    total = totals(blocks, run)
    print_table(blocks, total)
    if run.heap_mb:
        print("heap in use at each block's end (malloc, MB): " +
              ", ".join(f"{h:.1f}" for h in run.heap_mb) +
              f"; growth after block 1 {run.heap_mb[-1] - run.heap_mb[0]:+.1f} MB")
    failures = check(total, args.frames, run)
    if run.error:
        print(f"run error: {run.error}")
    if args.check:
        print("\n".join(f"check failed: {f}" for f in failures) or "check passed")
    if args.json:
        args.json.write_text(json.dumps({
            "sequence": args.sequence, "mode": mode, "frames": args.frames, "block": args.block,
            "blocks": [asdict(b) for b in blocks], "totals": total, "error": run.error,
            "failures": failures, "rss_samples": run.samples,
            "heap_mb": run.heap_mb}, indent=1) + "\n")
    return 1 if run.error or (args.check and failures) else 0


if __name__ == "__main__":
    sys.exit(main())
