#!/usr/bin/env python3
"""Render a .glb with Mitsuba 3 (path tracer) and write a linear float EXR + JSON timing.

Mitsuba cannot read glTF, so this script reads the .glb itself (a small, spec-following
reader: nodes/TRS/matrices, meshes with triangle primitives, metallic-roughness materials,
KHR_materials_emissive_strength, KHR_materials_specular, KHR_lights_punctual, perspective
cameras) and builds the Mitsuba scene in memory. It does NOT go through Blender, so a
Cycles-vs-Mitsuba disagreement also checks Blender's glTF importer.

    $PEERS_VENV/bin/python tools/peers/mitsuba_render.py SCENE.glb --out OUT.exr \
        [--res 320 240] [--spp 64] [--max-bounces 8] [--seed 0] [--variant auto] \
        [--light-weights uniform|power] [--json OUT.json]

Mapping glTF -> Mitsuba
  * emissive material (emissiveFactor * emissiveStrength > 0): 'area' emitter with that
    RGB radiance (one-sided, along the geometric face normal = glTF winding). glTF
    doubleSided=true emitters cannot be two-sided in Mitsuba: reported in the JSON.
  * metallic == 0 and specularFactor == 0            -> 'diffuse' (Lambert)
  * metallic == 0 and specularFactor > 0              -> 'roughplastic' (GGX, alpha=r^2,
                                                        IOR 1.5, specular_reflectance=specularFactor)
  * otherwise                                         -> 'principled' (base_color, metallic,
                                                        roughness, specular=0.5*specularFactor)
    doubleSided materials are wrapped in 'twosided'. Textures are ignored (reported).
  * point -> 'point' (intensity = color * cd / 683 W/sr), spot -> 'spot' (same intensity,
    cutoff_angle = outerConeAngle, beam_width = innerConeAngle; Mitsuba's falloff is linear
    in angle, Blender/Cycles uses a smoothstep; glTF suggests a smooth curve: edges differ),
    directional -> 'directional' (irradiance = color * lux / 683 W/m^2). 683 lm/W is what
    Blender's exporter/importer use in their default 'SPEC' lighting mode.
    KHR_lights_punctual 'range' is ignored (Blender ignores it too).
  * camera: 'perspective', fov = yfov, fov_axis 'y'; glTF cameras look down -Z with +X
    right, Mitsuba's look down +Z with +X left: to_world = node @ diag(-1, 1, -1).
  * film: hdrfilm RGB float32, box reconstruction filter (1 px, matches cycles_render.py),
    sampler 'independent', integrator 'path' with max_depth = max_bounces + 2
    (Cycles' max_bounces counts bounces after direct lighting: 0 = direct light only,
    which is Mitsuba's max_depth 2), Russian roulette at Mitsuba's default rr_depth 5.
  * light selection: Mitsuba picks emitters uniformly by default ('uniform'); with
    --light-weights power each emitter gets sampling_weight = its approximate power
    (luminance), i.e. power-proportional light selection. Within an area emitter the point
    is chosen by area.

Variants: 'auto' uses llvm_ad_rgb when a libLLVM >= 17 is registered with ldconfig
(drjit 1.5 emits llvm.minimum intrinsics that LLVM 15 - Debian 12's default - cannot
select; Debian 12 has libllvm19 as a package), else scalar_rgb. The LLVM variant JIT
compiles on the first render, so it renders twice and reports both; t_render_s is the
second (warm-kernel) render, t_render_cold_s the first.
"""
import argparse
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np

WATTS_TO_LUMENS = 683.0


# ----------------------------------------------------------------------------
# minimal glTF 2.0 (.glb) reader
# ----------------------------------------------------------------------------
COMP = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
NCOMP = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4, 'MAT2': 4, 'MAT3': 9, 'MAT4': 16}


def read_glb(path):
    with open(path, 'rb') as f:
        data = f.read()
    magic, version, length = struct.unpack_from('<III', data, 0)
    if magic != 0x46546C67:
        raise ValueError(f'{path}: not a .glb file')
    off = 12
    js, binchunk = None, None
    while off < length:
        clen, ctype = struct.unpack_from('<II', data, off)
        chunk = data[off + 8: off + 8 + clen]
        if ctype == 0x4E4F534A:
            js = json.loads(chunk.decode('utf-8'))
        elif ctype == 0x004E4942:
            binchunk = chunk
        off += 8 + clen
    return js, binchunk


def accessor(gl, binchunk, idx):
    acc = gl['accessors'][idx]
    dt = np.dtype(COMP[acc['componentType']])
    nc = NCOMP[acc['type']]
    count = acc['count']
    if 'bufferView' not in acc:
        return np.zeros((count, nc), dt)
    bv = gl['bufferViews'][acc['bufferView']]
    if bv.get('buffer', 0) != 0:
        raise NotImplementedError('only single-buffer .glb supported')
    start = bv.get('byteOffset', 0) + acc.get('byteOffset', 0)
    stride = bv.get('byteStride', 0) or dt.itemsize * nc
    if stride == dt.itemsize * nc:
        a = np.frombuffer(binchunk, dtype=dt, count=count * nc, offset=start).reshape(count, nc)
    else:
        rows = [np.frombuffer(binchunk, dtype=dt, count=nc, offset=start + i * stride) for i in range(count)]
        a = np.stack(rows)
    if acc.get('normalized'):
        a = a.astype(np.float32) / np.iinfo(dt).max
    if acc.get('sparse'):
        raise NotImplementedError('sparse accessors')
    return a


def quat_to_mat(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def node_local(n):
    if 'matrix' in n:
        return np.array(n['matrix'], dtype=np.float64).reshape(4, 4).T  # column-major
    m = np.eye(4)
    s = np.array(n.get('scale', [1, 1, 1]), dtype=np.float64)
    r = quat_to_mat(n.get('rotation', [0, 0, 0, 1]))
    m[:3, :3] = r * s[None, :]
    m[:3, 3] = n.get('translation', [0, 0, 0])
    return m


def walk(gl):
    """Yield (node_index, world_matrix) for every node of the default scene."""
    scene = gl.get('scene', 0)
    roots = gl['scenes'][scene]['nodes'] if gl.get('scenes') else range(len(gl['nodes']))
    stack = [(r, np.eye(4)) for r in roots]
    while stack:
        i, parent = stack.pop()
        n = gl['nodes'][i]
        w = parent @ node_local(n)
        yield i, w
        for c in n.get('children', []):
            stack.append((c, w))


def material_info(gl, mid):
    """Plain-dict summary of a glTF material (defaults per spec)."""
    if mid is None:
        return dict(name='default', base=[1, 1, 1], metallic=1.0, roughness=1.0, spec=1.0,
                    emission=[0, 0, 0], double_sided=False, textured=False)
    m = gl['materials'][mid]
    pbr = m.get('pbrMetallicRoughness', {})
    ext = m.get('extensions', {})
    strength = ext.get('KHR_materials_emissive_strength', {}).get('emissiveStrength', 1.0)
    emission = [c * strength for c in m.get('emissiveFactor', [0, 0, 0])]
    textured = any(k in pbr for k in ('baseColorTexture', 'metallicRoughnessTexture')) or \
        any(k in m for k in ('emissiveTexture', 'normalTexture', 'occlusionTexture'))
    return dict(name=m.get('name', f'mat{mid}'),
                base=list(pbr.get('baseColorFactor', [1, 1, 1, 1])[:3]),
                metallic=float(pbr.get('metallicFactor', 1.0)),
                roughness=float(pbr.get('roughnessFactor', 1.0)),
                spec=float(ext.get('KHR_materials_specular', {}).get('specularFactor', 1.0)),
                emission=emission, double_sided=bool(m.get('doubleSided', False)), textured=textured,
                unsupported=sorted(k for k in ext if k not in ('KHR_materials_emissive_strength',
                                                                  'KHR_materials_specular')))


def luminance(rgb):
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]


# ----------------------------------------------------------------------------
# Mitsuba scene construction
# ----------------------------------------------------------------------------
def build_scene(mi, glb, width, height, spp, max_bounces, seed, light_weights, report, lambert=False):
    gl, binchunk = read_glb(glb)
    T = mi.ScalarTransform4f
    scene = {'type': 'scene'}
    report.update(meshes=0, triangles=0, emissive_triangles=0, area_emitters=0, point=0, spot=0,
                  directional=0, cameras=0, textured_materials_ignored=0, two_sided_emitters_as_one_sided=0,
                  unsupported_extensions=[])
    bsdf_cache = {}

    def bsdf_for(info):
        key = json.dumps(info, sort_keys=True)
        if key in bsdf_cache:
            return bsdf_cache[key]
        base = {'type': 'rgb', 'value': [float(c) for c in info['base']]}
        if info['metallic'] <= 0.0 and info['spec'] <= 0.0:
            b = {'type': 'diffuse', 'reflectance': base}
        elif info['metallic'] <= 0.0:
            b = {'type': 'roughplastic', 'distribution': 'ggx', 'alpha': max(info['roughness'] ** 2, 1e-4),
                 'int_ior': 1.5, 'ext_ior': 1.0, 'nonlinear': False, 'diffuse_reflectance': base,
                 'specular_reflectance': {'type': 'rgb', 'value': [info['spec']] * 3}}
        else:
            b = {'type': 'principled', 'base_color': base, 'metallic': info['metallic'],
                 'roughness': max(info['roughness'], 1e-3), 'specular': 0.5 * info['spec']}
        if info['double_sided']:
            b = {'type': 'twosided', 'bsdf': b}
        obj = mi.load_dict(b)
        bsdf_cache[key] = obj
        return obj

    scene_lo, scene_hi = np.full(3, np.inf), np.full(3, -np.inf)
    cam_done = False
    for ni, W in walk(gl):
        node = gl['nodes'][ni]
        if 'mesh' in node:
            mesh = gl['meshes'][node['mesh']]
            nmat = W[:3, :3]
            normal_mat = np.linalg.inv(nmat).T
            flip = np.linalg.det(nmat) < 0
            for pi, prim in enumerate(mesh['primitives']):
                if prim.get('mode', 4) != 4:
                    continue
                P = accessor(gl, binchunk, prim['attributes']['POSITION']).astype(np.float64)
                P = P @ nmat.T + W[:3, 3]
                if 'indices' in prim:
                    F = accessor(gl, binchunk, prim['indices']).reshape(-1, 3).astype(np.uint32)
                else:
                    F = np.arange(len(P), dtype=np.uint32).reshape(-1, 3)
                if flip:
                    F = F[:, ::-1].copy()
                N = None
                if 'NORMAL' in prim['attributes']:
                    N = accessor(gl, binchunk, prim['attributes']['NORMAL']).astype(np.float64) @ normal_mat.T
                    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-20)
                scene_lo = np.minimum(scene_lo, P.min(0))
                scene_hi = np.maximum(scene_hi, P.max(0))
                info = material_info(gl, prim.get('material'))
                if lambert and max(info['emission']) <= 0:
                    info.update(metallic=0.0, spec=0.0, roughness=1.0)
                if info['textured']:
                    report['textured_materials_ignored'] += 1
                for u in info.get('unsupported', []):
                    if u not in report['unsupported_extensions']:
                        report['unsupported_extensions'].append(u)
                props = mi.Properties()
                emissive = max(info['emission']) > 0
                if emissive:
                    # emitters: black/own BSDF, area emitter, geometric normals (flat)
                    props['bsdf'] = bsdf_for(info)
                    tri = P[F]
                    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
                    power = math.pi * area * luminance(info['emission'])
                    em = {'type': 'area', 'radiance': {'type': 'rgb', 'value': [float(c) for c in info['emission']]}}
                    if light_weights == 'power':
                        em['sampling_weight'] = float(max(power, 1e-12))
                    props['emitter'] = mi.load_dict(em)
                    report['area_emitters'] += 1
                    report['emissive_triangles'] += len(F)
                    if info['double_sided']:
                        report['two_sided_emitters_as_one_sided'] += 1
                    N = None  # emission sidedness uses the geometric normal in both renderers
                else:
                    props['bsdf'] = bsdf_for(info)
                has_n = N is not None
                m = mi.Mesh(f"{mesh.get('name', 'mesh')}_{ni}_{pi}", len(P), len(F), props=props,
                            has_vertex_normals=has_n, has_vertex_texcoords=False)
                p = mi.traverse(m)
                p['vertex_positions'] = _arr(mi, P.astype(np.float32).ravel(), 'f')
                p['faces'] = _arr(mi, F.ravel(), 'u')
                if has_n:
                    p['vertex_normals'] = _arr(mi, N.astype(np.float32).ravel(), 'f')
                p.update()
                scene[f'shape_{ni}_{pi}'] = m
                report['meshes'] += 1
                report['triangles'] += len(F)
        if 'camera' in node and not cam_done:
            cam = gl['cameras'][node['camera']]
            if cam['type'] != 'perspective':
                raise NotImplementedError('orthographic camera')
            per = cam['perspective']
            # remove scale from the camera frame
            R = W[:3, :3] / np.linalg.norm(W[:3, :3], axis=0, keepdims=True)
            Wc = np.eye(4)
            Wc[:3, :3] = R @ np.diag([-1.0, 1.0, -1.0])
            Wc[:3, 3] = W[:3, 3]
            scene['sensor'] = {
                'type': 'perspective', 'fov': math.degrees(per['yfov']), 'fov_axis': 'y',
                'near_clip': float(per.get('znear', 0.01)), 'far_clip': float(per.get('zfar', 1e5)),
                'to_world': T(Wc.tolist()),
                'film': {'type': 'hdrfilm', 'width': width, 'height': height, 'pixel_format': 'rgb',
                         'component_format': 'float32', 'rfilter': {'type': 'box'}},
                'sampler': {'type': 'independent', 'sample_count': spp, 'seed': seed},
            }
            cam_done = True
            report['cameras'] += 1
            report['camera_aspect_ratio_gltf'] = per.get('aspectRatio')
        ext = node.get('extensions', {}).get('KHR_lights_punctual')
        if ext is not None:
            L = gl['extensions']['KHR_lights_punctual']['lights'][ext['light']]
            col = np.array(L.get('color', [1, 1, 1]), dtype=np.float64)
            inten = float(L.get('intensity', 1.0)) / WATTS_TO_LUMENS
            rgb = [float(c) for c in col * inten]
            pos = W[:3, 3]
            fwd = -W[:3, 2] / max(np.linalg.norm(W[:3, 2]), 1e-20)
            if L['type'] == 'point':
                e = {'type': 'point', 'position': pos.tolist(), 'intensity': {'type': 'rgb', 'value': rgb}}
                report['point'] += 1
            elif L['type'] == 'spot':
                sp = L.get('spot', {})
                outer = sp.get('outerConeAngle', math.pi / 4)
                inner = min(sp.get('innerConeAngle', 0.0), outer * 0.999)
                R = W[:3, :3] / np.linalg.norm(W[:3, :3], axis=0, keepdims=True)
                Ws = np.eye(4)
                Ws[:3, :3] = R @ np.diag([-1.0, 1.0, -1.0])   # Mitsuba spot shines along +Z
                Ws[:3, 3] = pos
                e = {'type': 'spot', 'to_world': T(Ws.tolist()), 'intensity': {'type': 'rgb', 'value': rgb},
                     'cutoff_angle': math.degrees(outer), 'beam_width': math.degrees(inner)}
                report['spot'] += 1
            elif L['type'] == 'directional':
                e = {'type': 'directional', 'direction': fwd.tolist(), 'irradiance': {'type': 'rgb', 'value': rgb}}
                report['directional'] += 1
            else:
                continue
            scene[f'light_{ni}'] = e
    if not cam_done:
        raise ValueError('no camera in ' + glb)
    if light_weights == 'power':
        radius = 0.5 * float(np.linalg.norm(scene_hi - scene_lo))
        for k, v in scene.items():
            if isinstance(v, dict) and v.get('type') in ('point', 'spot', 'directional'):
                if v['type'] == 'point':
                    w = 4 * math.pi * luminance(v['intensity']['value'])
                elif v['type'] == 'spot':
                    w = 2 * math.pi * (1 - math.cos(math.radians(v['cutoff_angle']))) * luminance(v['intensity']['value'])
                else:
                    w = math.pi * radius ** 2 * luminance(v['irradiance']['value'])
                v['sampling_weight'] = float(max(w, 1e-12))
    scene['integrator'] = {'type': 'path', 'max_depth': max_bounces + 2}
    return scene


def _arr(mi, a, kind):
    if mi.variant().startswith('scalar'):
        return a
    return mi.Float(a) if kind == 'f' else mi.UInt32(a)


def pick_variant(requested):
    if requested != 'auto':
        return requested, None
    try:
        out = subprocess.run(['ldconfig', '-p'], capture_output=True, text=True, timeout=20).stdout
    except Exception:
        out = ''
    best = None
    for line in out.splitlines():
        m = re.search(r'libLLVM(?:-(\d+)|\.so\.(\d+))\S*\s.*=>\s*(\S+)', line)
        if m:
            ver = int(m.group(1) or m.group(2))
            if ver >= 17 and (best is None or ver > best[0]):
                best = (ver, m.group(3))
    env = os.environ.get('DRJIT_LIBLLVM_PATH')
    if env:
        return 'llvm_ad_rgb', env
    if best:
        os.environ['DRJIT_LIBLLVM_PATH'] = best[1]
        return 'llvm_ad_rgb', best[1]
    return 'scalar_rgb', None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('glb')
    ap.add_argument('--out', required=True)
    ap.add_argument('--json', default=None)
    ap.add_argument('--res', type=int, nargs=2, default=[320, 240], metavar=('W', 'H'))
    ap.add_argument('--spp', type=int, default=64)
    ap.add_argument('--max-bounces', type=int, default=8)
    ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--variant', default=os.environ.get('PEERS_MITSUBA_VARIANT', 'auto'),
                    help="auto | scalar_rgb | llvm_ad_rgb")
    ap.add_argument('--light-weights', choices=['uniform', 'power'], default='uniform')
    ap.add_argument('--threads', type=int, default=int(os.environ.get('PEERS_THREADS', '2')))
    ap.add_argument('--no-warm', action='store_true', help='LLVM variant: single (cold) render only')
    ap.add_argument('--half', action='store_true')
    ap.add_argument('--passes', type=int, default=1,
                    help='split --spp into this many passes (seeds seed..seed+passes-1) and average; '
                         'needed for high spp with the LLVM variant, which keeps a whole pass in memory')
    ap.add_argument('--lambert', action='store_true',
                    help='diagnostic: every non-emissive material becomes Lambert with its base colour')
    ap.add_argument('--repeat', type=int, default=1,
                    help='time this many (warm) renders, report the fastest')
    ap.add_argument('--role', default='test', help='free tag stored in the JSON')
    a = ap.parse_args()

    variant, llvm_lib = pick_variant(a.variant)
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(variant)
    try:
        dr.set_thread_count(a.threads)
    except Exception:
        pass
    report = {}
    t0 = time.perf_counter()
    sd = build_scene(mi, a.glb, a.res[0], a.res[1], a.spp, a.max_bounces, a.seed, a.light_weights, report,
                     lambert=a.lambert)
    t_convert = time.perf_counter() - t0
    t1 = time.perf_counter()
    scene = mi.load_dict(sd)
    t_load = time.perf_counter() - t1   # includes Mitsuba's BVH build

    if a.spp % a.passes:
        sys.exit('--spp must be a multiple of --passes')
    spp_pass = a.spp // a.passes

    def render():
        ts = time.perf_counter()
        cs = time.process_time()
        acc = None
        for k in range(a.passes):
            img = np.array(mi.render(scene, spp=spp_pass, seed=a.seed + k))  # np.array forces evaluation
            acc = img if acc is None else acc + img
        return acc / a.passes, time.perf_counter() - ts, time.process_time() - cs

    arr, t_cold, cpu_cold = render()
    runs = [dict(sampling=round(t_cold, 4), cpu=round(cpu_cold, 4), warm=False)]
    n_more = (a.repeat if variant.startswith('llvm') and not a.no_warm else a.repeat - 1)
    for _ in range(max(0, n_more)):
        arr2, t, c = render()
        runs.append(dict(sampling=round(t, 4), cpu=round(c, 4), warm=True))
    timed = [r for r in runs if r['warm']] or runs
    best = min(timed, key=lambda r: r['sampling'])
    t_warm = best['sampling'] if best['warm'] else None
    t_sampling = best['sampling']

    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, here)
    from metrics import write_exr
    os.makedirs(os.path.dirname(os.path.abspath(a.out)) or '.', exist_ok=True)
    write_exr(a.out, arr[..., :3], half=a.half)
    rec = dict(renderer='mitsuba', role=a.role, passes=a.passes, mitsuba=mi.__version__, variant=variant, llvm=llvm_lib and os.path.basename(llvm_lib),
               scene=os.path.splitext(os.path.basename(a.glb))[0], exr=os.path.basename(a.out), spp=a.spp,
               width=a.res[0], height=a.res[1], max_bounces=a.max_bounces, max_depth=a.max_bounces + 2,
               seed=a.seed, light_weights=a.light_weights, lambert=a.lambert, threads=a.threads, pixel_filter='box 1px',
               sampler='independent', t_convert_s=round(t_convert, 4), t_load_bvh_s=round(t_load, 4),
               t_render_cold_s=round(t_load + t_cold, 4), t_render_warm_s=None if t_warm is None else round(t_warm, 4),
               t_sampling_s=round(t_sampling, 4), t_sync_s=round(t_load, 4),
               t_render_s=round(t_load + t_sampling, 4), cpu_render_s=best['cpu'], repeats=runs,
               conversion=report)
    print('RESULT ' + json.dumps(rec), flush=True)
    if a.json:
        with open(a.json, 'w') as f:
            f.write(json.dumps(rec, indent=1) + '\n')


if __name__ == '__main__':
    main()
