#!/usr/bin/env python3
"""How long merging a split render takes, and how much memory: `myriad merge` of K parts.

    python3 tools/merge_bench.py [--parts 64] [--resolution 1920x1080] [--out target/merge-bench]
        [--myriad target/release/myriad]

Renders the built-in Cornell box at RESOLUTION as K one-sample parts (`render --samples i..i+1`,
direct light only, to keep the renders short), times `myriad merge` of all of them (wall and
CPU seconds, peak resident memory from wait4), checks the merged image against a one-machine
render of the same K samples bit for bit (`myriad diff`: MSE 0), prints one line per figure,
and deletes the parts. Only the Python standard library is used.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def timed(cmd):
    """(wall s, cpu s, peak MiB) of one run of `cmd`."""
    start = time.monotonic()
    pid = os.fork()
    if pid == 0:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.execvp(cmd[0], [str(c) for c in cmd])
    _, status, usage = os.wait4(pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed")
    return time.monotonic() - start, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--parts", type=int, default=64)
    ap.add_argument("--resolution", default="1920x1080")
    ap.add_argument("--out", type=Path, default=ROOT / "target/merge-bench")
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    args = ap.parse_args()
    m, out, k = args.myriad, args.out, args.parts
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    common = ["--resolution", args.resolution, "--max-depth", "1", "-q"]
    render_s = 0.0
    for i in range(k):
        wall, _, _ = timed([m, "render", *common, "--samples", f"{i}..{i + 1}", "-o", out / f"p{i:03}.part"])
        render_s += wall
    parts = sorted(out.glob("p*.part"))
    size = sum(p.stat().st_size for p in parts)
    wall, cpu, peak = timed([m, "merge", *parts, "-o", out / "merged.exr"])
    timed([m, "render", *common, "--spp", str(k), "-o", out / "one.exr", "--no-png"])
    diff = subprocess.run([m, "diff", out / "merged.exr", out / "one.exr"], capture_output=True, text=True).stdout
    mse = re.search(r"^MSE\s+(\S+)", diff, re.M).group(1)
    print(f"parts          {k} of {args.resolution}, {size / 2**20:.0f} MiB in all ({size / k / 2**20:.1f} MiB each)")
    print(f"render parts   {render_s:.1f} s wall in all")
    print(f"merge          {wall:.2f} s wall, {cpu:.2f} s CPU, peak {peak:.0f} MiB")
    print(f"bit-identical  MSE {mse} against one render of the {k} samples")
    shutil.rmtree(out)


if __name__ == "__main__":
    main()
