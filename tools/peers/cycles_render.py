#!/usr/bin/env python3
"""Render a .glb with Blender Cycles (CPU) and write a linear float EXR + JSON timing.

Run with the peers venv's python (needs the `bpy` wheel):

    $PEERS_VENV/bin/python tools/peers/cycles_render.py SCENE.glb --out OUT.exr \
        [--res 320 240] [--spp 64] [--max-bounces 8] [--seed 0] [--light-tree on|off] \
        [--threads 2] [--emission-sides gltf|two] [--json OUT.json]

What it does
  * fresh empty Blender file (no World -> black background), glTF import with
    export_import_convert_lighting_mode='SPEC' (the importer default: glTF cd/lux -> W,
    W/m^2 with 683 lm/W; this is the exact inverse of the exporter's default).
  * glTF-conformance fixes after import (all printed in the JSON under "fixes"):
      - point/spot radius (shadow_soft_size) = 0 and sun angle = 0: glTF punctual lights
        are delta lights; the importer leaves Blender's defaults (sun angle 0.526 deg).
      - emission sidedness ('gltf', default): emissive materials with doubleSided=false
        (the importer turns that into use_backface_culling=True, which Cycles ignores)
        get their emission masked on back faces (Mix Shader driven by Geometry.Backfacing,
        which keeps Cycles' emission estimate for the light tree exact) and
        emission_sampling='FRONT'; doubleSided=true emitters get 'FRONT_BACK'.
        '--emission-sides two' keeps stock Cycles behaviour (both sides emit) but still
        sets emission_sampling='FRONT_BACK' explicitly.
        Either way emission_sampling is explicit because Cycles' default 'AUTO' silently
        drops emitters whose estimated strength is <= 0.5 from light sampling.
  * Cycles: CPU, N threads, fixed seed, no denoising, no adaptive sampling, no clamping
    (direct/indirect clamp 0), filter_glossy 0, light threshold 0 (override with
    --light-threshold), all bounce limits = --max-bounces (transparent too), caustics on,
    no path guiding, box pixel filter 1 px (override with --filter), sampling pattern left
    at the Blender default and reported.
  * Colour management: view transform 'Standard', look 'None', exposure 0, gamma 1;
    output is OpenEXR 32-bit float RGB (ZIP), which Blender writes scene-linear.

Timing (JSON): t_import_s (glTF import + fixes, not part of render), t_render_total_s
(bpy.ops.render.render wall time), t_sync_s (render start -> first sample: scene sync,
BVH, light tree), t_bvh_s, t_light_tree_s (from Cycles' progress messages), and
t_sampling_s (first sample -> finished). t_render_s is what metrics.py uses
(= t_render_total_s, i.e. including BVH/light-tree build).
"""
import argparse
import json
import os
import sys
import time

try:
    import bpy
except ImportError:  # pragma: no cover
    sys.exit("cycles_render.py must run with a python that has the `bpy` module "
             "(e.g. the peers venv: $PEERS_VENV/bin/python)")


def parse():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('glb')
    ap.add_argument('--out', required=True, help='output .exr')
    ap.add_argument('--json', default=None, help='also write the JSON record here')
    ap.add_argument('--res', type=int, nargs=2, default=[320, 240], metavar=('W', 'H'))
    ap.add_argument('--spp', type=int, default=64)
    ap.add_argument('--max-bounces', type=int, default=8)
    ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--light-tree', choices=['on', 'off'], default='on')
    ap.add_argument('--threads', type=int, default=int(os.environ.get('PEERS_THREADS', '2')))
    ap.add_argument('--emission-sides', choices=['gltf', 'two'], default='gltf')
    ap.add_argument('--no-emitter-sampling', action='store_true',
                    help="emissive meshes are found by BSDF rays only (emission_sampling NONE): Cycles' "
                         "next-event estimation to an emitter inside rough glass overestimates (2.3 %% at "
                         "roughness 0.45, 9.7 %% at 0.8), so lamps-in-glass references are made without it")
    ap.add_argument('--light-threshold', type=float, default=0.0)
    ap.add_argument('--filter', default='box', choices=['box', 'gaussian', 'blackman_harris'])
    ap.add_argument('--filter-width', type=float, default=1.0)
    ap.add_argument('--half', action='store_true', help='write half-float EXR instead of 32-bit')
    ap.add_argument('--lambert', action='store_true',
                    help='diagnostic: make every non-emissive Principled BSDF pure Lambert with its base '
                         'colour (metallic 0, specular 0, roughness 1) to compare light transport '
                         'without BSDF-model differences')
    ap.add_argument('--repeat', type=int, default=1,
                    help='render this many times in the same process; timings are the fastest run '
                         '(this 2-vCPU VM shows large run-to-run time variation)')
    ap.add_argument('--role', default='test', help="free tag stored in the JSON (metrics.py uses 'ref')")
    return ap.parse_args()


def make_one_sided(mat):
    """Mask Principled emission on back faces; keep Cycles' emission estimate exact."""
    nt = mat.node_tree
    out = next((n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL' and n.is_active_output), None)
    if out is None or not out.inputs['Surface'].is_linked:
        return False
    src = out.inputs['Surface'].links[0].from_socket
    # back-face shader: the same BSDF without emission. Emitters exported from Blender
    # are black, so a black diffuse is exact for them; for general materials copy the
    # Principled node and zero its emission.
    src_node = src.node
    if src_node.type == 'BSDF_PRINCIPLED':
        back = nt.nodes.new('ShaderNodeBsdfPrincipled')
        for inp in src_node.inputs:
            if inp.name in back.inputs and hasattr(inp, 'default_value'):
                try:
                    back.inputs[inp.name].default_value = inp.default_value
                except (TypeError, AttributeError):
                    pass
            for l in inp.links:
                nt.links.new(l.from_socket, back.inputs[inp.name])
        back.distribution = src_node.distribution
        back.subsurface_method = src_node.subsurface_method
        back.inputs['Emission Strength'].default_value = 0.0
        for l in list(back.inputs['Emission Strength'].links):
            nt.links.remove(l)
    else:
        back = nt.nodes.new('ShaderNodeBsdfDiffuse')
        back.inputs['Color'].default_value = (0, 0, 0, 1)
    geo = nt.nodes.new('ShaderNodeNewGeometry')
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(geo.outputs['Backfacing'], mix.inputs['Fac'])
    nt.links.new(src, mix.inputs[1])          # Fac = 0 (front) -> original
    nt.links.new(back.outputs[0], mix.inputs[2])  # Fac = 1 (back)  -> no emission
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return True


def material_emits(mat):
    if not mat.node_tree:
        return False
    for n in mat.node_tree.nodes:
        if n.type == 'BSDF_PRINCIPLED':
            s = n.inputs['Emission Strength']
            c = n.inputs['Emission Color']
            if (s.is_linked or s.default_value > 0) and (c.is_linked or max(c.default_value[:3]) > 0):
                return True
        if n.type == 'EMISSION':
            return True
    return False


def main():
    a = parse()
    t0 = time.perf_counter()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(a.glb), export_import_convert_lighting_mode='SPEC')
    sc = bpy.context.scene
    fixes = {'light_radius_zeroed': 0, 'sun_angle_zeroed': 0, 'one_sided_emitters': 0,
             'two_sided_emitters': 0}
    for ld in bpy.data.lights:
        if ld.type in ('POINT', 'SPOT') and ld.shadow_soft_size != 0.0:
            ld.shadow_soft_size = 0.0
            fixes['light_radius_zeroed'] += 1
        if ld.type == 'SUN' and ld.angle != 0.0:
            ld.angle = 0.0
            fixes['sun_angle_zeroed'] += 1
    for mat in bpy.data.materials:
        if not material_emits(mat):
            continue
        one_sided = a.emission_sides == 'gltf' and mat.use_backface_culling
        if one_sided and make_one_sided(mat):
            mat.cycles.emission_sampling = 'FRONT'
            fixes['one_sided_emitters'] += 1
        else:
            mat.cycles.emission_sampling = 'FRONT_BACK'
            fixes['two_sided_emitters'] += 1
        if a.no_emitter_sampling:
            mat.cycles.emission_sampling = 'NONE'
            fixes['emitters_unsampled'] = fixes.get('emitters_unsampled', 0) + 1
    if a.lambert:
        fixes['lambert_materials'] = 0
        for mat in bpy.data.materials:
            if material_emits(mat) or not mat.node_tree:
                continue
            for n in mat.node_tree.nodes:
                if n.type == 'BSDF_PRINCIPLED':
                    n.inputs['Metallic'].default_value = 0.0
                    n.inputs['Specular IOR Level'].default_value = 0.0
                    n.inputs['Roughness'].default_value = 1.0
                    n.inputs['Coat Weight'].default_value = 0.0
                    n.inputs['Sheen Weight'].default_value = 0.0
                    n.inputs['Transmission Weight'].default_value = 0.0
                    fixes['lambert_materials'] += 1
    cams = [o for o in sc.objects if o.type == 'CAMERA']
    if not cams:
        sys.exit('no camera in ' + a.glb)
    sc.camera = sorted(cams, key=lambda o: o.name)[0]
    sc.world = None
    t_import = time.perf_counter() - t0

    r = sc.render
    r.engine = 'CYCLES'
    r.resolution_x, r.resolution_y = a.res
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.threads_mode = 'FIXED'
    r.threads = a.threads
    r.use_persistent_data = False
    r.film_transparent = False
    r.use_compositing = False
    r.use_sequencer = False
    c = sc.cycles
    c.device = 'CPU'
    c.samples = a.spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = a.seed
    c.use_animated_seed = False
    c.use_light_tree = (a.light_tree == 'on')
    c.light_sampling_threshold = a.light_threshold
    c.max_bounces = a.max_bounces
    c.diffuse_bounces = a.max_bounces
    c.glossy_bounces = a.max_bounces
    c.transmission_bounces = a.max_bounces
    c.volume_bounces = a.max_bounces
    c.transparent_max_bounces = a.max_bounces
    c.min_light_bounces = 0
    c.min_transparent_bounces = 0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.use_guiding = False
    c.pixel_filter_type = a.filter.upper()
    c.filter_width = a.filter_width
    c.time_limit = 0.0
    vs = sc.view_settings
    vs.view_transform = 'Standard'
    vs.look = 'None'
    vs.exposure = 0.0
    vs.gamma = 1.0
    im = r.image_settings
    im.file_format = 'OPEN_EXR'
    im.color_mode = 'RGB'
    im.color_depth = '16' if a.half else '32'
    im.exr_codec = 'ZIP'

    events = []

    def on_stats(*args):
        events.append((time.perf_counter(), str(args[0]) if args else ''))

    def on_mark(name):
        return lambda *args: events.append((time.perf_counter(), '@' + name))

    bpy.app.handlers.render_stats.append(on_stats)
    bpy.app.handlers.render_pre.append(on_mark('pre'))
    bpy.app.handlers.render_post.append(on_mark('post'))

    def first(pred):
        return next((t for t, m in events if pred(m)), None)

    def dt(x, y):
        return round(y - x, 4) if (x is not None and y is not None) else None

    runs = []
    for _ in range(max(1, a.repeat)):
        events.clear()
        t1 = time.perf_counter()
        c1 = time.process_time()
        bpy.ops.render.render(write_still=False)
        t_total = time.perf_counter() - t1
        cpu = time.process_time() - c1
        t_pre = first(lambda m: m == '@pre') or t1
        t_sample0 = first(lambda m: '| Sample 0/' in m)
        t_fin = first(lambda m: m.endswith('| Finished')) or first(lambda m: m == '@post')
        t_bvh0 = first(lambda m: 'Updating Scene BVH' in m)
        t_bvh1 = first(lambda m: 'Updating Scene BVH | Copying BVH to device' in m)
        t_lt0 = first(lambda m: m.endswith('| Updating Lights'))
        t_lt1 = first(lambda m: 'Updating Integrator' in m)
        runs.append(dict(total=round(t_total, 4), cpu=round(cpu, 4), sync=dt(t_pre, t_sample0),
                         bvh=dt(t_bvh0, t_bvh1), light_tree=dt(t_lt0, t_lt1), sampling=dt(t_sample0, t_fin)))
    best = min(runs, key=lambda r: r['total'])

    os.makedirs(os.path.dirname(os.path.abspath(a.out)) or '.', exist_ok=True)
    img = bpy.data.images['Render Result']
    img.save_render(filepath=os.path.abspath(a.out), scene=sc)

    rec = dict(
        renderer='cycles', role=a.role, blender=bpy.app.version_string, scene=os.path.splitext(os.path.basename(a.glb))[0],
        exr=os.path.basename(a.out), spp=a.spp, width=a.res[0], height=a.res[1],
        max_bounces=a.max_bounces, seed=a.seed, light_tree=(a.light_tree == 'on'), threads=a.threads,
        emission_sides=a.emission_sides, light_threshold=a.light_threshold, lambert=a.lambert,
        pixel_filter=f'{c.pixel_filter_type} {c.filter_width}px', sampling_pattern=c.sampling_pattern,
        t_import_s=round(t_import, 4), t_render_total_s=best['total'], t_render_s=best['total'],
        t_sync_s=best['sync'], t_bvh_s=best['bvh'], t_light_tree_s=best['light_tree'],
        t_sampling_s=best['sampling'], cpu_render_s=best['cpu'], repeats=runs, fixes=fixes,
        n_mesh_objects=sum(1 for o in sc.objects if o.type == 'MESH'),
        n_lights={t: sum(1 for o in sc.objects if o.type == 'LIGHT' and o.data.type == t)
                  for t in ('POINT', 'SPOT', 'SUN', 'AREA')},
    )
    s = json.dumps(rec)
    print('RESULT ' + s, flush=True)
    if a.json:
        with open(a.json, 'w') as f:
            f.write(json.dumps(rec, indent=1) + '\n')


if __name__ == '__main__':
    main()
