#!/usr/bin/env python3
"""How each light sampler's cost and error grow with the light count.

    cargo build --release && python3 tools/scaling.py [--out scaling] [--sizes 5,32,100,316,1000]
                                                      [--spp 16] [--resolution 160x120]

For every grid size it writes the Cornell box of scenes/cornell-5x5.ron with rows × cols
ceiling lamps (total power unchanged), runs `myriad compare` at equal spp against a reference
rendered with the tree, and collects render time per sample (the fastest of --seeds runs) and
relMSE (their mean) per sampler. `all` runs
up to 100 lights and `local` up to 10^4 (both are O(n) per shading point). Writes
OUT/scaling.md (a table) and OUT/scaling.svg (log-log: time per sample and relMSE against the
light count). Only the Python standard library is used.
"""

import argparse
import json
import math
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLERS = ["all", "uniform", "power", "local", "tree"]
COLORS = {"all": "#555555", "uniform": "#1f77b4", "power": "#ff7f0e", "local": "#2ca02c", "tree": "#d62728"}
LIMITS = {"all": 100, "local": 10_000}


def grid_scene(side, out):
    text = (ROOT / "scenes/cornell-5x5.ron").read_text()
    text, n = re.subn(r"rows: \d+,\s*cols: \d+", f"rows: {side},\n            cols: {side}", text)
    assert n == 1, "scenes/cornell-5x5.ron no longer has one `rows: .., cols: ..` grid"
    path = out / f"cornell-{side}x{side}.ron"
    path.write_text(text)
    return path


def run(side, args, out):
    n = side * side
    samplers = [s for s in SAMPLERS if n <= LIMITS.get(s, math.inf)]
    scene = grid_scene(side, out)
    cmd = [
        str(ROOT / "target/release/myriad"), "compare", str(scene),
        "--samplers", ",".join(samplers), "--spp", str(args.spp), "--resolution", args.resolution,
        "--reference-spp", str(args.reference_spp), "--reference-sampler", "tree", "--seeds", str(args.seeds),
        "--out-dir", str(out / f"{side}x{side}"),
    ]
    print(f"{n} lights: {' '.join(cmd[1:])}", file=sys.stderr)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    report = json.loads((out / f"{side}x{side}" / "report.json").read_text())
    w, h = (int(x) for x in args.resolution.split("x"))
    rows = {}
    for s in report["samplers"]:
        # The fastest seed: interference from other work on the machine only ever slows a run.
        ns = min(1e9 * r["seconds"] / (w * h * r["spp"]) for r in s["runs"])
        rows[s["sampler"]] = {
            "ns_per_sample": ns,
            "rel_mse": s["rel_mse"]["mean"],
            "build_ms": 1e3 * s["build_seconds"],
            "bytes": s["memory_bytes"],
        }
    return n, rows


def table(results):
    lines = ["| lights | sampler | ns / sample | relMSE | build (ms) | memory (B) |", "|---:|---|---:|---:|---:|---:|"]
    for n, rows in results:
        for s in SAMPLERS:
            if s in rows:
                r = rows[s]
                lines.append(
                    f"| {n} | {s} | {r['ns_per_sample']:.0f} | {r['rel_mse']:.4g} | {r['build_ms']:.2f} | {r['bytes']} |"
                )
    return "\n".join(lines) + "\n"


def svg(results, title):
    """Two log-log panels side by side, one polyline per sampler."""
    W, H, M = 420, 320, 60
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{2 * W}" height="{H + 40}" font-family="sans-serif" font-size="12">']
    parts.append(f'<text x="{W}" y="18" text-anchor="middle" font-size="14">{title}</text>')
    xs = [n for n, _ in results]
    for panel, (key, label) in enumerate([("ns_per_sample", "time per sample (ns)"), ("rel_mse", "relMSE")]):
        ox = panel * W
        ys = [r[key] for _, rows in results for r in rows.values() if r[key] > 0]
        x0, x1 = math.log10(min(xs)), math.log10(max(xs))
        y0, y1 = math.floor(math.log10(min(ys))), math.ceil(math.log10(max(ys)))
        y1 = max(y1, y0 + 1)

        def px(x):
            return ox + M + (math.log10(x) - x0) / max(x1 - x0, 1e-9) * (W - 1.5 * M)

        def py(y):
            return 30 + (H - M) * (1 - (math.log10(y) - y0) / (y1 - y0))

        parts.append(f'<rect x="{ox + M}" y="30" width="{W - 1.5 * M}" height="{H - M}" fill="none" stroke="#000"/>')
        for d in range(math.floor(x0), math.ceil(x1) + 1):
            if x0 - 1e-9 <= d <= x1 + 1e-9:
                parts.append(f'<text x="{px(10 ** d):.1f}" y="{H - M + 45}" text-anchor="middle">1e{d}</text>')
        for d in range(y0, y1 + 1):
            parts.append(f'<text x="{ox + M - 5}" y="{py(10 ** d) + 4:.1f}" text-anchor="end">1e{d}</text>')
        parts.append(f'<text x="{ox + M + (W - 1.5 * M) / 2}" y="{H + 28}" text-anchor="middle">lights</text>')
        parts.append(f'<text x="{ox + M + 5}" y="46">{label}</text>')
        for i, s in enumerate(SAMPLERS):
            pts = [(n, rows[s][key]) for n, rows in results if s in rows and rows[s][key] > 0]
            if not pts:
                continue
            path = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in pts)
            parts.append(f'<polyline points="{path}" fill="none" stroke="{COLORS[s]}" stroke-width="2"/>')
            for x, y in pts:
                parts.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="3" fill="{COLORS[s]}"/>')
            if panel == 0:
                parts.append(f'<text x="{ox + W - M}" y="{60 + 16 * i}" fill="{COLORS[s]}" text-anchor="end">{s}</text>')
    parts.append("</svg>")
    return "\n".join(parts) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="scaling")
    ap.add_argument("--sizes", default="5,10,32,100,316,1000", help="grid sides (n = side²)")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--seeds", type=int, default=3, help="renders per sampler; time is the fastest, relMSE the mean")
    ap.add_argument("--reference-spp", type=int, default=256)
    ap.add_argument("--resolution", default="160x120")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = [run(int(side), args, out) for side in args.sizes.split(",")]
    title = f"Cornell grid, {args.resolution}, {args.spp} spp, full GI"
    (out / "scaling.md").write_text(f"# {title}\n\n" + table(results))
    (out / "scaling.svg").write_text(svg(results, title))
    print(table(results))
    print(f"wrote {out}/scaling.md and {out}/scaling.svg", file=sys.stderr)


if __name__ == "__main__":
    main()
