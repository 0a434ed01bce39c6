#!/usr/bin/env python3
"""This checkout's myriad against the build of an earlier commit, on the terms of a speed
claim: the same images, then instructions and CPU time a sample, as ratios from one run.

    python3 tools/against_build.py REV SCENE... [--sampler power] [--flags '--caustics off']
        [--old-flags ''] [--pairs 5] [--spp 64] [--resolution 320x240] [--threads 2]
        [--no-time] [--myriad target/release/myriad]

REV (a commit, e.g. the one an issue started from) is checked out into a worktree under
`target/against/` and built there once (a full release build, a few minutes). For each scene:

1. **Same images**: both builds render it at 80 × 60, 8 spp, seed 1, and `myriad diff` gives
   the relMSE between them. A ratio means something only between renders of the same image:
   up to the last bits of a sum taken in another order that is ~1e-16; a changed sampler or
   feature shows as 1e-6 and more. Pick `--sampler`, `--flags` (this build's) and
   `--old-flags` (REV's, whose options may be fewer) so that the two agree: a render that
   differs is reported, and its ratios are marked.
2. **Instructions a sample**: the difference of a 12- and a 4-spp render at 80 × 60 on one
   thread under `valgrind --tool=cachegrind` (as `tools/per_sample.py` counts them), over the
   samples between; the ratio old ÷ new is how many times fewer this build executes.
3. **CPU a sample** (unless `--no-time`): `--pairs` pairs of whole renders at `--resolution`,
   `--spp`, `--threads`, seed 1, the two builds in turn (old, new, old, new, ...), user +
   system seconds of each from the operating system's accounting of the finished child. The
   ratio is taken pair by pair, which keeps it meaningful while the machine's speed drifts;
   the median and the range of the pairs are printed. On a shared machine the pairs spread
   by ±10 %: differences below a few per cent are the instruction count's to tell.

Only the Python standard library, git, cargo and valgrind are used.
"""

import argparse
import shlex
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from peer_table import cpu_of, rel_mse  # noqa: E402
from per_sample import sample_costs  # noqa: E402

#: Above this relMSE between the two builds' renders they are not the same image.
SAME = 1e-9


def built(rev):
    """The release myriad of commit `rev`, checked out and built under target/against/."""
    sha = subprocess.run(["git", "rev-parse", "--verify", f"{rev}^{{commit}}"], cwd=ROOT, capture_output=True,
                         text=True)
    if sha.returncode != 0:
        sys.exit(f"{rev} is no commit of this repository")
    sha = sha.stdout.strip()
    tree = ROOT / "target/against" / sha[:12]
    binary = tree / "target/release/myriad"
    if not binary.exists():
        if not tree.exists():
            subprocess.run(["git", "worktree", "add", "--detach", str(tree), sha], cwd=ROOT, check=True,
                           capture_output=True)
        print(f"building {rev} ({sha[:12]}) in {tree.relative_to(ROOT)} ...", file=sys.stderr, flush=True)
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=tree, check=True)
    return str(binary)


def render(myriad, scene, out, sampler, flags, spp, resolution, threads):
    """The command rendering `scene` once, quietly, into `out`."""
    return [myriad, "--threads", str(threads), "render", scene, "--spp", str(spp), "--resolution", resolution,
            "--seed", "1", "--sampler", sampler, "-o", out, "-q", *flags]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rev", help="the earlier commit")
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--sampler", default="power")
    ap.add_argument("--flags", default="--caustics off", help="this build's render options")
    ap.add_argument("--old-flags", default="", help="the earlier build's render options")
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--resolution", default="320x240")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--no-time", action="store_true", help="skip the timed pairs")
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    args = ap.parse_args()
    if not Path(args.myriad).exists():
        sys.exit(f"{args.myriad} is missing: cargo build --release")
    old, new = built(args.rev), args.myriad
    flags = {old: shlex.split(args.old_flags) + ["--max-depth", "9"], new: shlex.split(args.flags) + ["--max-depth", "9"]}
    print(f"{args.rev} against this build, --sampler {args.sampler}, this build's flags '{args.flags}', "
          f"{args.rev}'s '{args.old_flags}'")
    print("| scene | relMSE between the two | instructions a sample, old → new | fewer | "
          f"CPU s ({args.resolution}, {args.spp} spp, {args.threads} threads), old / new medians | faster, median (range) |")
    print("|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            name = Path(scene).name
            a, b = str(Path(tmp) / "old.exr"), str(Path(tmp) / "new.exr")
            for myriad, out in [(old, a), (new, b)]:
                subprocess.run(render(myriad, scene, out, args.sampler, flags[myriad], 8, "80x60", 1), check=True,
                               capture_output=True)
            diff = rel_mse(new, b, a)
            mark = "" if diff <= SAME else " (not the same image)"
            i_old, i_new = (sample_costs(m, scene, args.sampler, "80x60", flags[m])[0] for m in (old, new))
            timed = "| – | –"
            if not args.no_time:
                times = {old: [], new: []}
                for _ in range(args.pairs):
                    for myriad in (old, new):
                        out = str(Path(tmp) / "timed.exr")
                        cmd = render(myriad, scene, out, args.sampler, flags[myriad], args.spp, args.resolution,
                                     args.threads)
                        times[myriad].append(cpu_of(cmd))
                ratios = sorted(o / n for o, n in zip(times[old], times[new]))
                timed = (f"| {statistics.median(times[old]):.2f} / {statistics.median(times[new]):.2f} "
                         f"| {statistics.median(ratios):.3f}× ({ratios[0]:.3f}–{ratios[-1]:.3f})")
            print(f"| {name} | {diff:.3g}{mark} | {i_old:.0f} → {i_new:.0f} | {i_old / i_new:.3f}× {timed} |",
                  flush=True)


if __name__ == "__main__":
    main()
