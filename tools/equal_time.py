#!/usr/bin/env python3
"""Does the default sampler win at equal time? `myriad compare` on every shipped scene.

    python3 tools/equal_time.py [--time 2 | --spp N] [--seeds 2] [--resolution 160x120]
        [--reference-spp 512] [--out target/equal-time] [--also local] [SCENE ...]

Runs `myriad compare SCENE --samplers uniform,power,tree,cells --time T --seeds K` (the reference
rendered once with `tree` at `--reference-spp` and cached per scene) on `scenes/*.ron`
(except the 102 400-lamp grid, whose uniform runs say little in seconds) and the Blender
exports in `tests/data/blender/`, or on the scenes given, and prints each sampler's
efficiency (1 / (relMSE · seconds) of the means over the seeds), the default's (`cells`) ratio to the
best of `uniform` and `power`, and its ratio to `tree`; `--also S,...` adds samplers and each
one's ratio to `tree`. A last column gives the default's ratio to the best of `uniform` and
`power` again from compare's `99.9 %` efficiency, which leaves out each image's 0.1 % of
pixels of largest error: on a scene with caustics (materials.glb) a firefly that no light
sampler reaches holds 99 % of the full relMSE and decides the first ratio by chance.

With `--spp N` every run renders N samples instead and the efficiency is still
1 / (relMSE · seconds): for an unbiased estimator relMSE falls as 1/spp, so this measures
the same quantity as equal time, and since at equal spp every sampler traces the same
camera rays and BSDF directions, a rare caustic firefly lands in every sampler's image
alike instead of in whichever happened to render one pass more. Only the Python standard
library is used.
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT = "cells"
SAMPLERS = ["uniform", "power", "tree", DEFAULT]


def default_scenes():
    rons = sorted(p for p in (ROOT / "scenes").glob("*.ron") if "320x320" not in p.name)
    return rons + sorted((ROOT / "tests/data/blender").glob("*.glb"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--time", default="2")
    ap.add_argument("--spp", help="equal spp instead of equal time (the efficiency is the same quantity)")
    ap.add_argument("--seeds", default="2")
    ap.add_argument("--resolution", default="160x120")
    ap.add_argument("--reference-spp", default="512")
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    ap.add_argument("--out", type=Path, default=ROOT / "target/equal-time")
    ap.add_argument("--also", default="", help="more samplers, comma-separated, each compared with tree")
    args = ap.parse_args()
    also = [s for s in args.also.split(",") if s and s not in SAMPLERS]
    samplers = SAMPLERS + also
    if not Path(args.myriad).exists():
        sys.exit(f"{args.myriad} is missing: cargo build --release")
    ratios = [DEFAULT] + also
    rows = ["| scene | lights | " + " | ".join(samplers) + f" | {DEFAULT} ÷ best of uniform, power |"
            + "".join(f" {s} ÷ tree |" for s in ratios) + " the same, 99.9 % of pixels |",
            "|---|---:|" + "---:|" * (len(samplers) + 2 + len(ratios))]
    for scene in args.scenes or default_scenes():
        out = args.out / scene.stem
        budget = ["--spp", args.spp] if args.spp else ["--time", args.time]
        cmd = [args.myriad, "compare", str(scene), "--samplers", ",".join(samplers), *budget,
               "--seeds", args.seeds, "--resolution", args.resolution, "--reference-spp", args.reference_spp,
               "--reference-sampler", "tree", "--out-dir", str(out), "-q"]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        report = json.loads((out / "report.json").read_text())
        eff = {s["sampler"]: s["efficiency"]["mean"] for s in report["samplers"]}
        info = subprocess.run([args.myriad, "info", str(scene)], capture_output=True, text=True).stdout
        lights = next((l.split()[1] for l in info.splitlines() if l.startswith("lights")), "?")
        ratio = eff[DEFAULT] / max(eff["uniform"], eff["power"])
        trimmed = {s["sampler"]: s["efficiency_trimmed"] for s in report["samplers"]}
        trimmed_ratio = trimmed[DEFAULT] / max(trimmed["uniform"], trimmed["power"])
        rows.append(f"| {scene.name} | {lights} | " + " | ".join(f"{eff[s]:.3g}" for s in samplers) + f" | {ratio:.2f} |"
                    + "".join(f" {eff[s] / eff['tree']:.2f} |" for s in ratios) + f" {trimmed_ratio:.2f} |")
        print(rows[-1], flush=True)
    table = "\n".join(rows) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "table.md").write_text(table)
    print(table)


if __name__ == "__main__":
    main()
