#!/usr/bin/env python3
"""Error and instructions per sample, measured without a clock: samplers compared on a
machine whose timings wander by ±10 % from run to run.

    python3 tools/per_sample.py SCENE REFERENCE.exr [--samplers power,cells] [--spp 64]
        [--seeds 16] [--resolution 160x120] [--myriad target/release/myriad] [--flags '...']
        [--misses]

For each sampler: relMSE · spp at `--spp` samples over `--seeds` seeds (`myriad compare`
against REFERENCE, which must be a converged render at the same resolution), the spread of
the seeds' values (a heavy tail there is fireflies), the same without each image's worst
0.1 % of pixels (compare's `99.9 %`, which a firefly shared by every sampler does not
decide), and the instructions one sample costs, counted by `valgrind --tool=cachegrind` on one thread as the difference between a 12-spp
and a 4-spp render (so loading, building and writing cancel out). Their product is the
instructions a sample spends for a given error; a lower one is a more efficient sampler as
far as instruction counts go. Cache misses are not in it: `--misses` also counts, with
cachegrind's cache model, the misses a sample takes in a 32 KiB first-level cache and in a
512 KiB last level (one core's L2 on the development machines), where a scene whose data
outgrows the L2 spends its time; or check with an equal-time run, `tools/equal_time.py`,
where the machine is quiet. Only the Python standard library and valgrind are used.
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


#: cachegrind's cache model for `--misses`: a 32 KiB, 8-way first-level data cache and a
#: 512 KiB, 8-way last level (one core's L2), 64-byte lines.
CACHES = ["--cache-sim=yes", "--D1=32768,8,64", "--LL=524288,8,64"]


def counted(cmd, misses=False, valgrind=()):
    """Instructions of running `cmd` under cachegrind (and, with `misses`, its data misses in
    the first level and in the L2-sized last level): a tuple. `valgrind`: more of its options."""
    sim = CACHES if misses else ["--cache-sim=no"]
    run = ["valgrind", "--tool=cachegrind", *sim, *valgrind, "--cachegrind-out-file=/dev/null", *cmd]
    err = subprocess.run(run, capture_output=True, text=True, check=True).stderr
    keys = [r"I\s+refs", r"D1\s+misses", r"LLd\s+misses"] if misses else [r"I\s+refs"]
    found = [re.search(k + r":\s+([\d,]+)", err) for k in keys]
    if not all(found):
        sys.exit(f"no counts in valgrind's output:\n{err}")
    return tuple(int(m.group(1).replace(",", "")) for m in found)


def costs(myriad, scene, sampler, spp, resolution, flags, misses=False):
    """`counted` for a one-thread myriad render of `spp` samples per pixel."""
    return counted([myriad, "render", scene, "--spp", str(spp), "--resolution", resolution, "--threads", "1",
                    "--sampler", sampler, "-o", str(Path(tempfile.gettempdir()) / "per-sample.exr"), "-q", *flags],
                   misses)


def sample_costs(myriad, scene, sampler, resolution, flags, misses=False, spp=(4, 12)):
    """What one sample costs (`costs`' tuple): the difference of renders at the two sample
    counts `spp` over the samples between, so that loading, building and writing cancel out."""
    w, h = (int(x) for x in resolution.split("x"))
    low, high = (costs(myriad, scene, sampler, n, resolution, flags, misses) for n in spp)
    return tuple((b - a) / (w * h * (spp[1] - spp[0])) for a, b in zip(low, high))


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
    ap.add_argument("--misses", action="store_true",
                    help="also count data cache misses a sample (first level, and an L2-sized last level)")
    args = ap.parse_args()
    flags = shlex.split(args.flags)
    if not Path(args.myriad).exists():
        sys.exit(f"{args.myriad} is missing: cargo build --release")
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([args.myriad, "compare", args.scene, "--samplers", args.samplers, "--spp", str(args.spp),
                        "--seeds", str(args.seeds), "--resolution", args.resolution, "--reference", args.reference,
                        "--out-dir", out, "-q", *flags], check=True, stdout=subprocess.DEVNULL)
        report = json.loads((Path(out) / "report.json").read_text())
    miss_heads = " | L1 misses a sample | L2 misses a sample" if args.misses else ""
    print(f"| sampler | relMSE · spp (mean of {args.seeds} seeds) | seeds, lowest – highest | instructions a sample "
          f"| product, ÷ the lowest | relMSE · spp, 99.9 % of pixels | its product, ÷ the lowest{miss_heads} |")
    print("|---|---:|---:|---:|---:|---:|---:|" + ("---:|---:|" if args.misses else ""))
    rows = []
    for s in report["samplers"]:
        errors = sorted(r["rel_mse"] * args.spp for r in s["runs"])
        per_sample = sample_costs(args.myriad, args.scene, s["sampler"], args.resolution, flags, args.misses)
        trimmed = s["rel_mse_trimmed"]["mean"] * args.spp
        rows.append((s["sampler"], s["rel_mse"]["mean"] * args.spp, errors, per_sample, trimmed))
    best = min(e * c[0] for _, e, _, c, _ in rows)
    best_trimmed = min(t * c[0] for _, _, _, c, t in rows)
    for name, e, errors, c, t in rows:
        i = c[0]
        misses = "".join(f" | {m:.1f}" for m in c[1:])
        print(f"| {name} | {e:.4g} | {errors[0]:.4g} – {errors[-1]:.4g} | {i:.0f} | {e * i / best:.2f} "
              f"| {t:.4g} | {t * i / best_trimmed:.2f}{misses} |")


if __name__ == "__main__":
    main()
