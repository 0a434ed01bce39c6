#!/usr/bin/env python3
"""myriad against Cycles and Mitsuba on the same Blender exports, in one run.

    python3 tools/peer_table.py [--scenes cornell_grid_7,materials] [--spp 64] [--seeds 2]
        [--peers tools/peers] [--peers-python ~/.cache/myriad-peers/bin/python]
        [--out target/peers] [--doc docs/performance.md]

For each scene `tests/data/blender/NAME.glb` it renders, at 320×240 and `--spp` samples with
8 bounces (myriad: 9 scattering events), every seed of `--seeds`:
  * myriad with `cells` (the default), `tree`, `uniform` and `power`, and `power` without
    light paths (`--caustics off`: chosen and traced as Mitsuba's power run, like for like);
  * Cycles 5.0 with its light tree on and off (`cycles_render.py`, Blender's own importer);
  * Mitsuba 3 with uniform and power light weights (`mitsuba_render.py`, llvm_ad_rgb when a
    libLLVM ≥ 17 is installed: `apt-get install libllvm19`; scalar_rgb otherwise), and with
    power light weights in scalar_rgb, one path at a time.
and measures each image against Cycles' 1024-spp render `tests/data/blender/refs/NAME.cycles.exr`
with `myriad diff` (relMSE = mean((x − ref)² / (ref² + 0.01))). CPU seconds: myriad's whole
process (start-up, load and build included); the peers' render only (`cpu_render_s` of their
JSON: Blender's start-up and import, and Mitsuba's kernel compilation, excluded), which
favours them. Efficiency = 1 / (relMSE · CPU s), means over the seeds.

Writes `OUT/NAME/...` (every image and JSON) and `OUT/table.md`, prints the table, and with
`--doc` replaces the text between `<!-- peers:begin -->` and `<!-- peers:end -->` in it.
Peer renders already in OUT with the same settings are reused (`--fresh` renders them again).
Only the Python standard library is used here; the peers need their venv
(`tools/peers/setup_venv.sh`).
"""

import argparse
import json
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RES = (320, 240)
BOUNCES = 8


def cpu_of(cmd):
    """CPU seconds of one run of `cmd` (fork + wait4, so the figure is the child's own)."""
    pid = os.fork()
    if pid == 0:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        try:
            os.execvp(cmd[0], [str(c) for c in cmd])
        finally:
            os._exit(127)
    _, status, usage = os.wait4(pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed (exit {os.waitstatus_to_exitcode(status)})")
    return usage.ru_utime + usage.ru_stime


def rel_mse(myriad, image, reference):
    out = subprocess.run([myriad, "diff", image, reference], capture_output=True, text=True, check=True).stdout
    return float(re.search(r"relMSE\s+(\S+)", out).group(1))


#: myriad's rows: (label, file tag, options). The last one chooses lights as Mitsuba's power
#: run does and traces no light paths (Mitsuba has none): a sample's cost like for like.
MYRIAD_RUNS = [
    ("myriad `cells` (default)", "cells", ["--sampler", "cells"]),
    ("myriad `tree`", "tree", ["--sampler", "tree"]),
    ("myriad `uniform`", "uniform", ["--sampler", "uniform"]),
    ("myriad `power`", "power", ["--sampler", "power"]),
    ("myriad `power`, no light paths", "power_plain", ["--sampler", "power", "--caustics", "off"]),
]


def myriad_rows(myriad, glb, ref, out, spp, seeds):
    rows = []
    for label, tag, flags in MYRIAD_RUNS:
        runs = []
        for seed in seeds:
            exr = out / f"myriad_{tag}_{seed}.exr"
            cmd = [myriad, "render", glb, "--resolution", f"{RES[0]}x{RES[1]}", "--spp", spp, "--max-depth",
                   BOUNCES + 1, *flags, "--seed", seed, "-q", "-o", exr, "--no-png"]
            cpu = cpu_of(cmd)
            runs.append((rel_mse(myriad, exr, ref), cpu))
        rows.append((label, runs))
    return rows


def peer_rows(args, myriad, glb, ref, out):
    if not Path(args.peers_python).exists():
        print(f"note: no peers venv at {args.peers_python}; peers skipped", file=sys.stderr)
        return []
    rows = []
    peers = [
        ("Cycles 5.0, light tree", "cycles_render.py", ["--light-tree", "on"]),
        ("Cycles 5.0, tree off", "cycles_render.py", ["--light-tree", "off"]),
        ("Mitsuba 3, uniform", "mitsuba_render.py", ["--light-weights", "uniform"]),
        ("Mitsuba 3, power", "mitsuba_render.py", ["--light-weights", "power"]),
        # Mitsuba one path at a time: what its eight-lane LLVM build gains by its wavefront.
        ("Mitsuba 3, power, one path at a time", "mitsuba_render.py", ["--light-weights", "power", "--variant", "scalar_rgb"]),
    ]
    for label, script, extra in peers:
        runs = []
        for seed in args.seed_list:
            tag = re.sub(r"[^a-z0-9]+", "_", label.lower()).strip("_")
            exr, js = out / f"{tag}_{seed}.exr", out / f"{tag}_{seed}.json"
            settings = {"spp": args.spp, "seed": seed, "extra": extra}
            if args.fresh or not (exr.exists() and js.exists() and json.loads(js.read_text()).get("table") == settings):
                cmd = [args.peers_python, Path(args.peers) / script, glb, "--out", exr, "--json", js, "--res",
                       RES[0], RES[1], "--spp", args.spp, "--max-bounces", BOUNCES, "--seed", seed, *extra]
                subprocess.run([str(c) for c in cmd], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                record = json.loads(js.read_text())
                record["table"] = settings
                js.write_text(json.dumps(record, indent=1))
            record = json.loads(js.read_text())
            runs.append((rel_mse(myriad, exr, ref), record["cpu_render_s"]))
        variant = ""
        if script.startswith("mitsuba"):
            variant = f" ({json.loads(js.read_text()).get('variant', '?')})"
        rows.append((label + variant, runs))
    return rows


def table(scene, rows, spp):
    mean = lambda xs: sum(xs) / len(xs)
    stats = [(label, mean([r for r, _ in runs]), mean([c for _, c in runs])) for label, runs in rows]
    best = stats[0][1] * stats[0][2]
    lines = [f"**{scene}** ({RES[0]}×{RES[1]}, {spp} spp, {BOUNCES} bounces; relMSE against Cycles at 1024 spp)",
             "", "| renderer | relMSE | CPU s | efficiency | myriad default ÷ it |", "|---|---:|---:|---:|---:|"]
    for label, rel, cpu in stats:
        lines.append(f"| {label} | {rel:.4f} | {cpu:.2f} | {1 / (rel * cpu):.1f} | {(rel * cpu) / best:.2f} |")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="cornell_grid_7,materials")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--peers", default=str(ROOT / "tools" / "peers"))
    ap.add_argument("--peers-python", default=str(Path.home() / ".cache/myriad-peers/bin/python"))
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    ap.add_argument("--out", default=str(ROOT / "target/peers"))
    ap.add_argument("--doc", help="page to put the table into, between the peers markers (docs/performance.md)")
    ap.add_argument("--fresh", action="store_true", help="render the peers again even if their images are there")
    args = ap.parse_args()
    args.seed_list = list(range(1, args.seeds + 1))
    if not Path(args.myriad).exists():
        sys.exit(f"{args.myriad} is missing: cargo build --release")
    text = ""
    for scene in args.scenes.split(","):
        glb, ref = ROOT / f"tests/data/blender/{scene}.glb", ROOT / f"tests/data/blender/refs/{scene}.cycles.exr"
        out = Path(args.out) / scene
        out.mkdir(parents=True, exist_ok=True)
        rows = myriad_rows(args.myriad, glb, ref, out, args.spp, args.seed_list)
        rows += peer_rows(args, args.myriad, glb, ref, out)
        text += table(scene, rows, args.spp) + "\n"
        print(table(scene, rows, args.spp), flush=True)
    Path(args.out, "table.md").write_text(text)
    if args.doc:
        readme = Path(args.doc).read_text()
        begin, end = "<!-- peers:begin -->", "<!-- peers:end -->"
        if begin not in readme or end not in readme:
            sys.exit(f"{args.doc} has no {begin} … {end} markers")
        head, rest = readme.split(begin, 1)
        Path(args.doc).write_text(head + begin + "\n" + text + rest[rest.index(end):])


if __name__ == "__main__":
    main()
