#!/usr/bin/env python3
"""Where a sample's instructions go: by source line, file or function, or within one function
by its machine instructions, counted without a clock.

    python3 tools/line_costs.py SCENE [--by line|file|function] [--top 40] [--ours]
        [--asm FUNCTION] [--against OTHER_MYRIAD] [--myriad target/release/myriad]
        [--sampler cells] [--resolution 80x60] [--flags '--max-depth 9']

Two one-thread renders of SCENE under `valgrind --tool=callgrind` (4 and 12 spp): the
difference of their counts over the samples in between is what a sample costs, loading,
building and writing cancelled out. A profile of functions spreads the path loop over a few
huge inlined functions; counts by source line (each line's own instructions, wherever it was
inlined) show which line of which file a sample pays for.

- `--by line` (the default), `--by file`, `--by function`: each one's own instructions a
  sample, the largest first, with the line's text for the repository's files.
- `--asm FUNCTION`: the function whose symbol is FUNCTION, else contains it (of several
  such, the one a sample spends most in), its instructions grouped by the source line
  `objdump -l` gives each, and how often it is called a sample.
- `--against OTHER`: the same counts for a second build, side by side, sorted by the
  difference (what a change moved, line by line).

Only the Python standard library, valgrind and (for `--asm`) binutils are used.
"""

import argparse
import collections
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
POSITION = re.compile(r"^(0x[0-9a-fA-F]+|[+-]\d+|\*|\d+)\s+(0x[0-9a-fA-F]+|[+-]\d+|\*|\d+)\s+(\d+)")


def callgrind(myriad, scene, spp, args, out):
    """Runs one render under callgrind with per-instruction counts into `out`."""
    cmd = ["valgrind", "--tool=callgrind", "--dump-instr=yes", f"--callgrind-out-file={out}", myriad, "render",
           scene, "--spp", str(spp), "--resolution", args.resolution, "--threads", "1", "--seed", "1", "--sampler",
           args.sampler, "-o", str(Path(out).with_suffix(".exr")), "-q", *shlex.split(args.flags)]
    subprocess.run(cmd, check=True, capture_output=True)


def position(text, last):
    """A callgrind position: absolute, relative to the last one, or the same."""
    if text == "*":
        return last
    if text[0] in "+-":
        return last + int(text)
    return int(text, 16) if text.startswith("0x") else int(text)


#: Which table of compressed names each callgrind key names from (files are shared by all
#: file keys, functions by both function keys).
NAME_KIND = {"fl": "file", "fi": "file", "fe": "file", "cfl": "file", "cfi": "file", "fn": "fn", "cfn": "fn",
             "ob": "ob", "cob": "ob"}


def named(table, kind, value):
    """A name in callgrind's compression: `(id) name` defines the id, `(id)` refers to it."""
    m = re.match(r"\((\d+)\)(?: (.*))?$", value)
    if not m:
        return value
    if m.group(2) is not None:
        table[(kind, m.group(1))] = m.group(2)
    return table.get((kind, m.group(1)), "?")


def self_costs(path):
    """Each instruction's own count: {(address, file, line, function): Ir}, the inclusive
    counts of calls left out."""
    table, costs = {}, collections.Counter()
    fl = fi = fn = ""
    addr = line = 0
    in_call = False
    for raw in open(path, encoding="utf-8", errors="replace"):
        key, _, value = raw.rstrip("\n").partition("=")
        if key in NAME_KIND:
            name = named(table, NAME_KIND[key], value)
            if key == "fl":
                fl = fi = name
            elif key == "fn":
                fn, fi = name, fl
            elif key in ("fi", "fe"):
                fi = name
            continue
        if key == "calls":
            in_call = True
            continue
        m = POSITION.match(raw)
        if not m:
            continue
        addr, line = position(m.group(1), addr), position(m.group(2), line)
        if in_call:
            in_call = False
            continue
        costs[(addr, fi, line, fn)] += int(m.group(3))
    return costs


def per_sample(myriad, args):
    """Each instruction's own count a sample: the 12-spp run's minus the 4-spp run's."""
    w, h = (int(x) for x in args.resolution.split("x"))
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for spp in (4, 12):
            out = str(Path(tmp) / f"cg{spp}.out")
            callgrind(myriad, args.scene, spp, args, out)
            runs.append(self_costs(out))
    samples = w * h * 8
    return {k: (runs[1][k] - runs[0][k]) / samples for k in set(runs[0]) | set(runs[1])}


def short(path):
    """A source path as it reads best: relative to the repository, else from its crate's `src/`."""
    if path.startswith(str(ROOT) + "/"):
        return path[len(str(ROOT)) + 1:]
    return "…/" + path.split("/src/")[-1] if "/src/" in path else path


def text_of(path, line):
    """The text of a repository file's line (nothing for other files, or line 0: code the
    debug information gives no line)."""
    if line < 1 or not path.startswith(str(ROOT)):
        return ""
    try:
        return Path(path).read_text().splitlines()[line - 1].strip()[:90]
    except (OSError, IndexError):
        return ""


def grouped(costs, by, ours):
    """Counts summed by line, file or function; with `ours`, the repository's files alone."""
    out = collections.Counter()
    for (_, fi, line, fn), c in costs.items():
        if not ours or fi.startswith(str(ROOT)):
            out[{"line": (fi, line), "file": (fi,), "function": (fn,)}[by]] += c
    return out


def label(key):
    """A line (with its text where it is the repository's), a file or a function, as printed."""
    if len(key) == 2:
        return f"{short(key[0])}:{key[1]}  {text_of(key[0], key[1])}"
    return short(key[0]) if key[0].startswith("/") else key[0]


def function_range(myriad, costs, name):
    """(start, size, symbol) of the function named `name` exactly, else of the copy whose
    symbol contains it that a sample spends most in (inlining leaves several)."""
    symbols = subprocess.run(["nm", "-C", "-S", myriad], capture_output=True, text=True, check=True).stdout
    found = [(int(s, 16), int(z, 16), rest) for s, z, t, rest in
             (ln.split(" ", 3) for ln in symbols.splitlines() if ln.count(" ") >= 3) if t in "tT" and name in rest]
    if not found:
        sys.exit(f"no function whose symbol contains {name!r} in {myriad}")

    def spent(f):
        return sum(c for (a, *_), c in costs.items() if f[0] <= a < f[0] + f[1])

    return max([f for f in found if f[2] == name] or found, key=spent)


def asm(myriad, costs, name, top):
    """One function's instructions grouped by the source line objdump gives each."""
    start, size, symbol = function_range(myriad, costs, name)
    dump = subprocess.run(["objdump", "-d", "-l", "-C", "--no-show-raw-insn", f"--start-address={start:#x}",
                           f"--stop-address={start + size:#x}", myriad], capture_output=True, text=True, check=True)
    by_addr = collections.Counter()
    for (a, *_), c in costs.items():
        if start <= a < start + size:
            by_addr[a] += c
    source, lines = None, collections.Counter()
    for ln in dump.stdout.splitlines():
        m = re.match(r"^(/\S+):(\d+)", ln)
        if m:
            source = (m.group(1), int(m.group(2)))
            continue
        m = re.match(r"\s*([0-9a-f]+):", ln)
        if m and source:
            lines[source] += by_addr.get(int(m.group(1), 16), 0)
    print(f"{symbol}: {sum(by_addr.values()):.0f} instructions a sample, called {by_addr.get(start, 0):.2f} times")
    if not by_addr:
        print("(no sample runs this copy: the function is inlined into its callers, or not called here)")
        return
    for key, c in lines.most_common(top):
        print(f"{c:9.1f}  {label(key)}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--by", choices=["line", "file", "function"], default="line")
    ap.add_argument("--top", type=int, default=40)
    ap.add_argument("--ours", action="store_true",
                    help="the repository's lines alone (intrinsics and libraries inlined into them left out)")
    ap.add_argument("--asm", metavar="FUNCTION", help="one function's instructions by source line")
    ap.add_argument("--against", metavar="OTHER_MYRIAD", help="a second build, side by side")
    ap.add_argument("--myriad", default=str(ROOT / "target/release/myriad"))
    ap.add_argument("--sampler", default="cells")
    ap.add_argument("--resolution", default="80x60")
    ap.add_argument("--flags", default="--max-depth 9", help="more options for both renders")
    args = ap.parse_args()
    for binary in filter(None, [args.myriad, args.against]):
        if not Path(binary).exists():
            sys.exit(f"{binary} is missing: cargo build --release")
    if not Path(args.scene).exists():
        sys.exit(f"{args.scene}: no such scene file")
    for tool in ["valgrind"] + (["nm", "objdump"] if args.asm else []):
        if not shutil.which(tool):
            sys.exit(f"{tool} is missing: apt-get install {'valgrind' if tool == 'valgrind' else 'binutils'}")
    costs = per_sample(args.myriad, args)
    print(f"{sum(costs.values()):.0f} instructions a sample ({args.scene}, {args.sampler}, {args.flags})")
    if args.asm:
        asm(args.myriad, costs, args.asm, args.top)
        return
    mine = grouped(costs, args.by, args.ours)
    if not args.against:
        for key, c in mine.most_common(args.top):
            print(f"{c:9.1f}  {label(key)}")
        return
    other = grouped(per_sample(args.against, args), args.by, args.ours)
    print(f"{sum(other.values()):.0f} instructions a sample with {args.against}")
    print(f"{'this':>9} {'other':>9} {'other − this':>13}")
    keys = sorted(set(mine) | set(other), key=lambda k: -abs(other[k] - mine[k]))
    for key in keys[:args.top]:
        print(f"{mine[key]:9.1f} {other[key]:9.1f} {other[key] - mine[key]:+13.1f}  {label(key)}")


if __name__ == "__main__":
    main()
