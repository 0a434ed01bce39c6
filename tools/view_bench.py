#!/usr/bin/env python3
"""What the viewer's window costs: `myriad view --exit-when-done` against a headless
`myriad render` of the same scene, size and spp, whole processes timed in turns (A B A B ...),
under an Xvfb of its own; and how long after the scene was built the first image was shown.

    python3 tools/view_bench.py [--scene S] [--resolution 320x240] [--spp 64] [--runs 5]

Needs Xvfb (apt-get install xvfb) and a release build (cargo build --release).
"""
import argparse, os, re, resource, statistics, subprocess, sys, tempfile, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MYRIAD = os.path.join(ROOT, "target", "release", "myriad")


def timed(cmd, env):
    """(wall s, CPU s, stdout) of one run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", help="scene file (default: the built-in Cornell box)")
    ap.add_argument("--resolution", default="320x240")
    ap.add_argument("--spp", default="64")
    ap.add_argument("--runs", type=int, default=5)
    a = ap.parse_args()
    display = next(f":{n}" for n in range(500, 600) if not os.path.exists(f"/tmp/.X11-unix/X{n}"))
    xvfb = subprocess.Popen(["Xvfb", display, "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while not os.path.exists(f"/tmp/.X11-unix/X{display[1:]}"):
            time.sleep(0.05)
        env = dict(os.environ, DISPLAY=display)
        tmp = tempfile.mkdtemp()
        scene = [a.scene] if a.scene else []
        common = scene + ["--resolution", a.resolution, "--spp", a.spp, "-q"]
        view = [MYRIAD, "view", *common, "--exit-when-done", "--out-dir", tmp]
        render = [MYRIAD, "render", *common, "-o", os.path.join(tmp, "r.exr"), "--no-png"]
        timed(view, env), timed(render, env)  # warm-up
        rows, firsts = [], []
        for _ in range(a.runs):
            v, r = timed(view, env), timed(render, env)
            rows.append((v[0] / r[0], v[1] / r[1]))
            m = re.search(r"first image ([\d.]+) (ms|s) after", v[2])
            firsts.append(float(m.group(1)) * (1 if m.group(2) == "ms" else 1000))
        med = lambda xs: statistics.median(xs)
        print(f"{a.scene or 'built-in cornell-5x5'}, {a.resolution}, {a.spp} spp, {a.runs} pairs")
        print(f"view / render, wall: median {med([w for w, _ in rows]):.3f} "
              f"(min {min(w for w, _ in rows):.3f}, max {max(w for w, _ in rows):.3f})")
        print(f"view / render, CPU:  median {med([c for _, c in rows]):.3f} "
              f"(min {min(c for _, c in rows):.3f}, max {max(c for _, c in rows):.3f})")
        print(f"first image after the scene was built: median {med(firsts):.1f} ms "
              f"(min {min(firsts):.1f}, max {max(firsts):.1f})")
    finally:
        xvfb.kill()


if __name__ == "__main__":
    sys.exit(main())
