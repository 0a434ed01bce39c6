#!/usr/bin/env python3
"""Image metrics for the peer renders (numpy only, plus OpenEXR or imageio to read EXR).

    python tools/peers/metrics.py compare REF.exr IMG.exr [IMG.exr ...] [--time-json]
    python tools/peers/metrics.py table RENDER_DIR [--out results.md]
    python tools/peers/metrics.py preview IMG.exr OUT.png [--exposure 0]

Definitions (per pixel p and colour channel c, averaged over all W*H*3 values):
    MSE     = mean((x - ref)^2)
    relMSE  = mean((x - ref)^2 / (ref^2 + 1e-2))
    eff     = 1 / (relMSE * t)      t = render wall time in seconds (render only, incl.
                                     BVH / light-tree build, excl. scene import / JIT warm-up)
    eff_cpu = 1 / (relMSE * cpu)    cpu = process CPU seconds of the same span (Mitsuba: CPU of
                                     the sampling + wall of the single-threaded scene load);
                                     steadier than wall time on a shared / throttled machine
    mean radiance ratio = mean(x) / mean(ref)  (whole image, all channels), and the same
                          per channel; used to check that two renderers agree.
Non-finite values in x are counted and replaced by 0 (they are reported).
"""
import argparse
import glob
import json
import math
import os
import sys

import numpy as np

REL_EPS = 1e-2


# ----------------------------------------------------------------------------
# EXR / PNG io
# ----------------------------------------------------------------------------
def read_exr(path):
    """Return float32 HxWx3 (RGB) linear image."""
    try:
        import OpenEXR
        with OpenEXR.File(path) as f:
            ch = f.parts[0].channels
            if 'RGB' in ch:
                a = np.asarray(ch['RGB'].pixels, dtype=np.float32)
            elif 'RGBA' in ch:
                a = np.asarray(ch['RGBA'].pixels, dtype=np.float32)[..., :3]
            else:
                names = [n for n in ('R', 'G', 'B') if n in ch]
                if len(names) != 3:
                    raise KeyError(f'{path}: no RGB channels in {list(ch)}')
                a = np.stack([np.asarray(ch[n].pixels, dtype=np.float32) for n in names], -1)
            return np.ascontiguousarray(a[..., :3])
    except ImportError:
        import imageio.v3 as iio
        a = iio.imread(path)
        return np.asarray(a, dtype=np.float32)[..., :3]


def write_exr(path, img, half=False):
    import OpenEXR
    img = np.ascontiguousarray(np.asarray(img, dtype=np.float16 if half else np.float32)[..., :3])
    header = {'compression': OpenEXR.ZIP_COMPRESSION, 'type': OpenEXR.scanlineimage}
    with OpenEXR.File(header, {'RGB': img}) as f:
        f.write(path)


def tonemap_srgb(img, exposure=0.0, reinhard=False):
    """Exposure, optional Reinhard x/(1+x) shoulder, clamp, sRGB OETF, 8-bit."""
    x = np.maximum(np.nan_to_num(img, nan=0, posinf=0, neginf=0) * (2.0 ** exposure), 0)
    if reinhard:
        x = x / (1.0 + x)
    x = np.clip(x, 0, 1)
    y = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (np.clip(y, 0, 1) * 255 + 0.5).astype(np.uint8)


def auto_exposure(img, key=0.18):
    """Exposure (stops) mapping the log-average luminance to `key`."""
    lum = 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]
    lum = lum[np.isfinite(lum)]
    la = math.exp(float(np.mean(np.log(lum + 1e-4))))
    return math.log2(key / la) if la > 0 else 0.0


def write_png(path, img, exposure=0.0, reinhard=False):
    from PIL import Image
    Image.fromarray(tonemap_srgb(img, exposure, reinhard)).save(path)


# ----------------------------------------------------------------------------
# metrics
# ----------------------------------------------------------------------------
def sanitize(x):
    bad = ~np.isfinite(x)
    n = int(bad.sum())
    if n:
        x = np.where(bad, 0.0, x)
    return x, n


def compare(ref, img):
    ref = ref.astype(np.float64)
    x, nbad = sanitize(img.astype(np.float64))
    if ref.shape != x.shape:
        raise ValueError(f'shape mismatch {ref.shape} vs {x.shape}')
    d2 = (x - ref) ** 2
    mse = float(d2.mean())
    rel = float((d2 / (ref ** 2 + REL_EPS)).mean())
    mref = ref.reshape(-1, 3).mean(0)
    mx = x.reshape(-1, 3).mean(0)
    return dict(mse=mse, relmse=rel, mean=float(mx.mean()), mean_ref=float(mref.mean()),
                mean_ratio=float(mx.mean() / mref.mean()) if mref.mean() > 0 else float('nan'),
                mean_ratio_rgb=[float(a / b) if b > 0 else float('nan') for a, b in zip(mx, mref)],
                nonfinite=nbad)


def efficiency(relmse, t):
    if not t or relmse <= 0:
        return float('nan')
    return 1.0 / (relmse * t)


# ----------------------------------------------------------------------------
# results table over a render directory
# ----------------------------------------------------------------------------
def load_records(d):
    recs = []
    for jp in sorted(glob.glob(os.path.join(d, '*.json'))):
        with open(jp) as f:
            r = json.load(f)
        r['_json'] = jp
        r['_exr'] = os.path.join(os.path.dirname(jp), r['exr'])
        recs.append(r)
    return recs


def label(r):
    if r['renderer'] == 'cycles':
        s = 'Cycles LT ' + ('on' if r['light_tree'] else 'off')
    else:
        s = f"Mitsuba {r.get('light_weights', '')} ({r.get('variant', '')})"
    if r.get('role') == 'converged':
        s += ' converged'
    return s


def table(d, ref_tag='ref'):
    recs = load_records(d)
    by_scene = {}
    for r in recs:
        by_scene.setdefault(r['scene'], []).append(r)
    rows = []
    for scene, rs in sorted(by_scene.items()):
        refs = [r for r in rs if r.get('role') == ref_tag]
        if not refs:
            print(f'# {scene}: no reference, skipped', file=sys.stderr)
            continue
        ref_rec = refs[0]
        ref = read_exr(ref_rec['_exr'])
        for r in rs:
            if r is ref_rec:
                continue
            m = compare(ref, read_exr(r['_exr']))
            t = r.get('t_render_s')
            cpu = r.get('cpu_render_s')
            if cpu is not None and r['renderer'] == 'mitsuba':
                cpu += r.get('t_sync_s') or 0.0
            rows.append(dict(scene=scene, renderer=label(r), role=r.get('role', ''), spp=r['spp'],
                             time_s=t, t_sync_s=r.get('t_sync_s'), cpu_s=cpu, mse=m['mse'], relmse=m['relmse'],
                             eff=efficiency(m['relmse'], t), eff_cpu=efficiency(m['relmse'], cpu),
                             mean_ratio=m['mean_ratio'],
                             mean_ratio_rgb=m['mean_ratio_rgb'], nonfinite=m['nonfinite'],
                             exr=os.path.basename(r['_exr'])))
        rows.append(dict(scene=scene, renderer=label(ref_rec) + ' (reference)', role='ref',
                         spp=ref_rec['spp'], time_s=ref_rec.get('t_render_s'), t_sync_s=ref_rec.get('t_sync_s'),
                         cpu_s=ref_rec.get('cpu_render_s'), mse=0.0, relmse=0.0, eff=float('nan'),
                         eff_cpu=float('nan'), mean_ratio=1.0, mean_ratio_rgb=[1, 1, 1],
                         nonfinite=0, exr=os.path.basename(ref_rec['_exr'])))
    return rows


def _f(x, fmt):
    return '' if x is None or not np.isfinite(x) else format(x, fmt)


def fmt_table(rows):
    out = ['| scene | renderer | spp | time s | sync s | CPU s | MSE | relMSE | eff 1/(relMSE*t) | '
           'eff CPU 1/(relMSE*cpu) | mean / ref mean |',
           '|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|']
    for r in rows:
        out.append(f"| {r['scene']} | {r['renderer']} | {r['spp']} | {_f(r['time_s'], '.2f')} | "
                   f"{_f(r['t_sync_s'], '.2f')} | {_f(r.get('cpu_s'), '.2f')} | {_f(r['mse'], '.4g')} | "
                   f"{_f(r['relmse'], '.4g')} | {_f(r['eff'], '.3g')} | {_f(r.get('eff_cpu'), '.3g')} | "
                   f"{_f(r['mean_ratio'], '.4f')} |")
    return '\n'.join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest='cmd', required=True)
    c = sub.add_parser('compare')
    c.add_argument('ref')
    c.add_argument('imgs', nargs='+')
    c.add_argument('--time', type=float, default=None, help='render time for the efficiency figure')
    t = sub.add_parser('table')
    t.add_argument('dir')
    t.add_argument('--json-out', default=None)
    p = sub.add_parser('preview')
    p.add_argument('exr')
    p.add_argument('png')
    p.add_argument('--exposure', default='auto', help="stops, or 'auto' (log-average -> 0.18)")
    p.add_argument('--reinhard', action='store_true', help='x/(1+x) shoulder after exposure')
    a = ap.parse_args()
    if a.cmd == 'compare':
        ref = read_exr(a.ref)
        for path in a.imgs:
            m = compare(ref, read_exr(path))
            m['file'] = path
            if a.time:
                m['eff'] = efficiency(m['relmse'], a.time)
            print(json.dumps(m))
    elif a.cmd == 'table':
        rows = table(a.dir)
        print(fmt_table(rows))
        if a.json_out:
            with open(a.json_out, 'w') as f:
                json.dump(rows, f, indent=1)
    elif a.cmd == 'preview':
        img = read_exr(a.exr)
        ev = auto_exposure(img) if a.exposure == 'auto' else float(a.exposure)
        write_png(a.png, img, ev, a.reinhard)
        print(json.dumps(dict(png=a.png, exposure_stops=ev, reinhard=a.reinhard)))


if __name__ == '__main__':
    main()
