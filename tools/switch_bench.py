#!/usr/bin/env python3
"""Does a switch pay? Renders with a switch off and on at equal samples, over seeds.

    python3 tools/switch_bench.py [--switch guiding|caustics] [--spp 64] [--seeds 3]
        [--resolution 320x240] [--threads 1] [--myriad target/release/myriad] [--other-myriad B]
        [SCENE[=REFERENCE] ...]

`--switch guiding` (the default) is path guiding, `--switch caustics` the connections through
smooth glass. For each scene (default: glass.glb, materials.glb, lobby.glb against their
Cycles references in tests/data/blender/refs/, and scenes/street.ron against a 4096-spp myriad
render with the switch at its default, made once and kept in target/switch-bench/), renders
`--seeds` seeds with `--SWITCH off` and `--SWITCH on` (max depth 9, as Cycles' 8 bounces),
and prints per mode the mean full relMSE over the seeds (fireflies included: they are the
point), each seed's relMSE, the CPU seconds (user + system of the renders, one thread by
default so that CPU is what is measured) and the efficiency 1 / (mean relMSE · mean CPU s);
the last column is on ÷ off efficiency. `--other-myriad B` renders the `off` runs with another
binary, without the switch (this issue's start, say). Only the Python standard library is
used.
"""

import argparse
import os
import resource
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLENDER = ROOT / "tests/data/blender"


def cpu_of(cmd):
    """Runs `cmd`; returns the CPU seconds its children took."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def rel_mse(myriad, image, reference):
    out = subprocess.run([myriad, "diff", str(image), str(reference)], check=True, capture_output=True, text=True)
    for line in out.stdout.splitlines():
        if line.startswith("relMSE"):
            return float(line.split()[1])
    sys.exit(f"no relMSE in: {out.stdout}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*")
    ap.add_argument("--switch", choices=["guiding", "caustics"], default="guiding")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--resolution", default="320x240")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    ap.add_argument("--other-myriad", help="binary for the runs with the switch off")
    ap.add_argument("--out", default=str(ROOT / "target/switch-bench"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scenes = args.scenes or [
        f"{BLENDER}/{n}.glb={BLENDER}/refs/{n}.cycles.exr" for n in ["glass", "materials", "lobby"]
    ] + [str(ROOT / "scenes/street.ron")]
    common = ["--resolution", args.resolution, "--max-depth", "9", "--threads", str(args.threads), "-q"]
    print(f"{'scene':<16} {'mode':<8} {'relMSE':>9} {'per seed':<32} {'CPU s':>7} {'efficiency':>10} {'ratio':>6}")
    for spec in scenes:
        scene, _, reference = spec.partition("=")
        name = Path(scene).stem
        if not reference:
            reference = out / f"{name}.reference.exr"
            if not reference.exists():
                print(f"{name}: rendering a 4096-spp reference …", file=sys.stderr)
                subprocess.run([args.myriad, "render", scene, "--spp", "4096", "--seed", "999",
                                "--resolution", args.resolution, "--max-depth", "9", "-q", "-o", str(reference)],
                               check=True, stdout=subprocess.DEVNULL)
        efficiency = {}
        for mode in ["off", "on"]:
            binary = args.other_myriad if mode == "off" and args.other_myriad else args.myriad
            switch = [] if binary != args.myriad else [f"--{args.switch}", mode]
            rels, cpu = [], 0.0
            for seed in range(1, args.seeds + 1):
                image = out / f"{name}.{args.switch}-{mode}.{seed}.exr"
                cpu += cpu_of([binary, "render", scene, "--spp", str(args.spp), "--seed", str(seed), *switch,
                               *common, "-o", str(image)])
                rels.append(rel_mse(args.myriad, image, reference))
            mean, cpu = sum(rels) / len(rels), cpu / args.seeds
            efficiency[mode] = 1.0 / (mean * cpu)
            ratio = f"{efficiency['on'] / efficiency['off']:.2f}" if mode == "on" else ""
            seeds = " ".join(f"{r:.3g}" for r in rels)
            print(f"{name:<16} {mode:<8} {mean:>9.4f} {seeds:<32} {cpu:>7.2f} {efficiency[mode]:>10.3f} {ratio:>6}",
                  flush=True)


if __name__ == "__main__":
    main()
