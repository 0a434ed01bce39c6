#!/usr/bin/env python3
"""Instructions a sample, myriad against Mitsuba 3, counted without a clock: where timings on a
shared machine wander by ±10 %, the count says how much work each renderer does a sample.

    python3 tools/peer_instructions.py SCENE.glb [--max-bounces 8] [--resolution 160x120]
        [--spp 4,20] [--sampler power] [--flags '--caustics off'] [--lambert]
        [--myriad target/release/myriad] [--peers-python ~/.cache/myriad-peers/bin/python]

Both renderers run on one thread under `valgrind --tool=cachegrind --cache-sim=no` at the two
sample counts of `--spp`, and the difference of their counts over the samples in between is
what a sample costs (loading, building and writing cancel out). Mitsuba (`llvm_ad_rgb`, through
`tools/peers/mitsuba_render.py` with `--light-weights power`, as `tools/peer_table.py` runs it)
compiles its kernels with LLVM the first time it meets them, some 3·10⁹ instructions a
kernel; each of its counted runs is therefore preceded by the same render outside valgrind,
which leaves the kernel in Dr.Jit's cache. `--max-bounces B` is Cycles' count (0: direct
light only; -1: the camera ray and the emitters it sees, for Mitsuba alone) and myriad's
`--max-depth B+1`; myriad renders with `--sampler` (default `power`, the choice Mitsuba is
given) and `--flags`. `--lambert` makes Mitsuba's materials Lambert's (a diagnostic of what
its BSDFs cost). Only the Python standard library and valgrind are used; Mitsuba needs the
peers' venv (`tools/peers/setup_venv.sh`).
"""

import argparse
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from per_sample import counted, sample_costs  # noqa: E402

MITSUBA = ROOT / "tools/peers/mitsuba_render.py"


def mitsuba_instructions(python, scene, spp, size, bounces, lambert, out):
    """Instructions of a one-thread Mitsuba render of `spp` samples per pixel, its kernel
    compiled and cached by an uncounted render first."""
    cmd = [python, str(MITSUBA), scene, "--out", out, "--res", str(size[0]), str(size[1]),
           "--spp", str(spp), "--threads", "1", f"--max-bounces={bounces}", "--no-warm",
           "--light-weights", "power"] + (["--lambert"] if lambert else [])
    subprocess.run(cmd, check=True, capture_output=True)
    # Code LLVM writes at run time is translated anew wherever it is rewritten.
    return counted(cmd, valgrind=["--smc-check=all-non-file"])[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--max-bounces", type=int, default=8)
    ap.add_argument("--resolution", default="160x120")
    ap.add_argument("--spp", default="4,20", help="the two sample counts, low,high")
    ap.add_argument("--sampler", default="power")
    ap.add_argument("--flags", default="", help="more arguments for myriad's render")
    ap.add_argument("--lambert", action="store_true", help="Mitsuba's materials as Lambert's")
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    ap.add_argument("--peers-python", default=str(Path.home() / ".cache/myriad-peers/bin/python"))
    args = ap.parse_args()
    size = [int(v) for v in args.resolution.split("x")]
    low, high = (int(v) for v in args.spp.split(","))
    samples = (high - low) * size[0] * size[1]
    rows = []
    if args.max_bounces >= 0:
        flags = ["--max-depth", str(args.max_bounces + 1)] + shlex.split(args.flags)
        per_sample = sample_costs(args.myriad, args.scene, args.sampler, args.resolution, flags, spp=(low, high))[0]
        rows.append((f"myriad ({args.sampler} {' '.join(flags)})", per_sample))
    if Path(args.peers_python).exists():
        with tempfile.TemporaryDirectory() as tmp:
            out = str(Path(tmp) / "mitsuba.exr")
            counts = [mitsuba_instructions(args.peers_python, args.scene, spp, size, args.max_bounces, args.lambert, out)
                      for spp in (low, high)]
        rows.append((f"Mitsuba (power, max_depth {args.max_bounces + 2}{', Lambert' if args.lambert else ''})",
                     (counts[1] - counts[0]) / samples))
    else:
        print(f"note: no peers venv at {args.peers_python}; Mitsuba skipped", file=sys.stderr)
    print(f"instructions a sample, {Path(args.scene).name} at {args.resolution}, {low} → {high} spp, one thread")
    for label, n in rows:
        print(f"{n:10.0f}  {label}")
    if len(rows) == 2:
        print(f"{rows[0][1] / rows[1][1]:10.2f}  myriad ÷ Mitsuba")


if __name__ == "__main__":
    main()
