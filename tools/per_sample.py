#!/usr/bin/env python3
"""Error and instructions per sample, measured without a clock: samplers compared on a
machine whose timings wander by ±10 % from run to run.

    python3 tools/per_sample.py SCENE REFERENCE.exr [--samplers power,cells] [--spp 64]
        [--seeds 16] [--resolution 160x120] [--myriad target/release/myriad] [--flags '...']

For each sampler: relMSE · spp at `--spp` samples over `--seeds` seeds (`myriad compare`
against REFERENCE, which must be a converged render at the same resolution), the spread of
the seeds' values (a heavy tail there is fireflies), the same without each image's worst
0.1 % of pixels (compare's `99.9 %`, which a firefly shared by every sampler does not
decide), and the instructions one sample costs, counted by `valgrind --tool=cachegrind` on one thread as the difference between a 12-spp
and a 4-spp render (so loading, building and writing cancel out). Their product is the
instructions a sample spends for a given error; a lower one is a more efficient sampler as
far as instruction counts go (cache misses are not counted: check with an equal-time run,
`tools/equal_time.py`, where the machine is quiet). Only the Python standard library and
valgrind are used.
"""

import argparse
import json
import re
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def instructions(myriad, scene, sampler, spp, resolution, flags):
    cmd = ["valgrind", "--tool=cachegrind", "--cache-sim=no", "--cachegrind-out-file=/dev/null", myriad,
           "render", scene, "--spp", str(spp), "--resolution", resolution, "--threads", "1",
           "--sampler", sampler, "-o", str(Path(tempfile.gettempdir()) / "per-sample.exr"), "-q", *flags]
    err = subprocess.run(cmd, capture_output=True, text=True, check=True).stderr
    refs = re.search(r"I\s+refs:\s+([\d,]+)", err)
    if not refs:
        sys.exit(f"no instruction count in valgrind's output:\n{err}")
    return int(refs.group(1).replace(",", ""))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("reference")
    ap.add_argument("--samplers", default="power,cells")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--resolution", default="160x120")
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    ap.add_argument("--flags", default="", help="more options for every render, e.g. '--max-memory 6'")
    args = ap.parse_args()
    flags = shlex.split(args.flags)
    if not Path(args.myriad).exists():
        sys.exit(f"{args.myriad} is missing: cargo build --release")
    w, h = (int(x) for x in args.resolution.split("x"))
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([args.myriad, "compare", args.scene, "--samplers", args.samplers, "--spp", str(args.spp),
                        "--seeds", str(args.seeds), "--resolution", args.resolution, "--reference", args.reference,
                        "--out-dir", out, "-q", *flags], check=True, stdout=subprocess.DEVNULL)
        report = json.loads((Path(out) / "report.json").read_text())
    print(f"| sampler | relMSE · spp (mean of {args.seeds} seeds) | seeds, lowest – highest | instructions a sample "
          "| product, ÷ the lowest | relMSE · spp, 99.9 % of pixels | its product, ÷ the lowest |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    rows = []
    for s in report["samplers"]:
        errors = sorted(r["rel_mse"] * args.spp for r in s["runs"])
        a = instructions(args.myriad, args.scene, s["sampler"], 4, args.resolution, flags)
        b = instructions(args.myriad, args.scene, s["sampler"], 12, args.resolution, flags)
        per_sample = (b - a) / (w * h * 8)
        trimmed = s["rel_mse_trimmed"]["mean"] * args.spp
        rows.append((s["sampler"], s["rel_mse"]["mean"] * args.spp, errors, per_sample, trimmed))
    best = min(e * i for _, e, _, i, _ in rows)
    best_trimmed = min(t * i for _, _, _, i, t in rows)
    for name, e, errors, i, t in rows:
        print(f"| {name} | {e:.4g} | {errors[0]:.4g} – {errors[-1]:.4g} | {i:.0f} | {e * i / best:.2f} "
              f"| {t:.4g} | {t * i / best_trimmed:.2f} |")


if __name__ == "__main__":
    main()
