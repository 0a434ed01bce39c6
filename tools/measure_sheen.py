#!/usr/bin/env python3
"""Measures Cycles' sheen lobe (Blender's Principled Sheen and Sheen BSDF, "Microfiber") and
writes the table myriad renders it with: src/material/tables/sheen.rs.

Run with a Python that has Blender's `bpy` module (the peers venv, tools/peers/setup_venv.sh),
from the repository root (about two minutes on two cores):

    ~/.cache/myriad-peers/bin/python tools/measure_sheen.py [--out src/material/tables/sheen.rs]

Cycles' sheen (Zeltner, Burley, Chiang 2022, "Practical Multiple-Scattering Sheen Using
Linearly Transformed Cosines") is a linearly transformed cosine: in the frame whose x axis is
the viewer's azimuth, the density of the incident direction is
D(ω) = max(z, 0)/π · (a / ((a·x + b·z)² + (a·y)² + z²))², and the lobe's value times the
cosine is albedo · D. The three numbers a, b and the albedo depend on cos θo and the sheen
roughness; Cycles reads them from a fitted table. This script measures them on Cycles itself:
an equirectangular camera 1 m above a 20 km plane that carries only a white Sheen BSDF sees
every cos θo at once (a Position pass tells which), and for each roughness node

  * a white world that only BSDF rays reach (world sampling off) gives the albedo: the lobe is
    sampled by its own density, so every sample weighs exactly the albedo (1 sample/pixel);
  * two delta suns (angle 0, strength 1; elevations 30° and 65°) give albedo · D(sun) per
    pixel, and a, b come from a least-squares fit of D over the pixels of each cos θo node.

The grid is 32 × 32 nodes, cos θo and roughness each at i/31 (roughness 0 is Cycles' 1e-3).
"""

import argparse
import math
import os
import sys
import tempfile

import bpy
import numpy as np
import OpenEXR
from mathutils import Vector

NODES = 32
RES = (1024, 512)
SUN_ELEVATIONS = (30.0, 65.0)
HELD_OUT_ELEVATION = 45.0  # a sun the fit does not see, to check it
CAMERA_HEIGHT = 1.0


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = 1
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = 2
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 0.01
    c.seed = 0
    scene.render.resolution_x, scene.render.resolution_y = RES
    scene.render.resolution_percentage = 100
    scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"  # Blender 5: multilayer EXR
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    scene.view_layers[0].use_pass_position = True

    bpy.ops.mesh.primitive_plane_add(size=20000.0, location=(0, 0, 0))
    mat = bpy.data.materials.new("sheen")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    sheen = nodes.new("ShaderNodeBsdfSheen")
    sheen.distribution = "MICROFIBER"
    sheen.inputs["Color"].default_value = (1, 1, 1, 1)
    out = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(sheen.outputs[0], out.inputs["Surface"])
    bpy.context.active_object.data.materials.append(mat)

    bpy.ops.object.camera_add(location=(0, 0, CAMERA_HEIGHT), rotation=(0, 0, 0))
    cam = bpy.context.active_object
    cam.data.type = "PANO"
    cam.data.panorama_type = "EQUIRECTANGULAR"
    scene.camera = cam

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.cycles.sampling_method = "NONE"
    scene.world = world

    bpy.ops.object.light_add(type="SUN")
    sun = bpy.context.active_object
    sun.data.angle = 0.0
    sun.data.energy = 1.0
    return sheen, world, sun


def render(path):
    bpy.context.scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    channels = {}
    for part in OpenEXR.File(path).parts:
        channels.update(part.channels)
    red = np.asarray(channels["ViewLayer.Combined"].pixels, dtype=np.float64)[..., 0].ravel()
    pos = np.stack([np.asarray(channels[f"ViewLayer.Position.{a}"].pixels, dtype=np.float64).ravel()
                    for a in "XYZ"], -1)
    return red, pos


def ltc(a, b, local):
    """Cycles' sheen density (with the cosine) at local directions `local` (…, 3)."""
    x, y, z = local[..., 0], local[..., 1], local[..., 2]
    len_sq = (a * x + b * z) ** 2 + (a * y) ** 2 + z ** 2
    return np.maximum(z, 0.0) / math.pi * (a / len_sq) ** 2


def local_frames(pos):
    """cos θo and the sheen's frame (x towards the viewer's azimuth) at hit points `pos`."""
    wi = np.array([0.0, 0.0, CAMERA_HEIGHT]) - pos
    wi /= np.linalg.norm(wi, axis=-1, keepdims=True)
    b = np.stack([-wi[:, 1], wi[:, 0], np.zeros(len(wi))], -1)  # N × wi with N = +z
    b /= np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-12)
    t = np.stack([b[:, 1], -b[:, 0], np.zeros(len(wi))], -1)  # B × N
    return wi[:, 2], t, b


def fit_ab(mu, d, locs, mu0, start):
    """a, b at cos θo = mu0 from samples (mu, measured density d at local light directions
    locs): Levenberg-Marquardt on the relative residual, with log a and b each linear in
    μ − mu0, from `start` (the neighbouring node's a, b)."""
    dm = mu - mu0

    def residual(q):
        model = ltc(np.exp(q[0] + q[1] * dm), q[2] + q[3] * dm, locs)
        return (model - d) / np.maximum(d, 1e-3)

    p = np.array([math.log(start[0]), 0.0, start[1], 0.0])
    r = residual(p)
    cost, damping = r @ r, 1e-3
    for _ in range(200):
        jac = np.empty((len(r), 4))
        for k in range(4):
            step = np.zeros(4)
            step[k] = 1e-6
            jac[:, k] = (residual(p + step) - r) / 1e-6
        jtj = jac.T @ jac
        delta = np.linalg.solve(jtj + damping * np.diag(np.diag(jtj) + 1e-12), -jac.T @ r)
        trial = residual(p + delta)
        if trial @ trial < cost:
            p, r, cost, damping = p + delta, trial, trial @ trial, damping * 0.3
            if np.abs(delta).max() < 1e-10:
                break
        else:
            damping *= 10.0
            if damping > 1e12:
                break
    return math.exp(p[0]), p[2]


def linear_at(x, y, x0):
    """The least-squares line through (x, y) evaluated at x0."""
    a = np.stack([np.ones_like(x), x - x0], -1)
    return np.linalg.lstsq(a, y, rcond=None)[0][0]


def measure(sheen, world, sun, tmp):
    table = np.zeros((NODES, NODES, 3))
    errors = []  # (held-out relative RMS, roughness node, cos θo node)
    half = 0.35 / (NODES - 1)
    for j in range(NODES):
        roughness = j / (NODES - 1)
        sheen.inputs["Roughness"].default_value = roughness
        world.node_tree.nodes["Background"].inputs["Color"].default_value = (1, 1, 1, 1)
        sun.hide_render = True
        albedo, pos = render(os.path.join(tmp, "furnace.exr"))
        hit = np.linalg.norm(pos, axis=-1) > 0
        mu, t, b = local_frames(pos[hit])
        albedo = albedo[hit]
        world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
        sun.hide_render = False
        lit, dirs = [], []
        for elevation in (*SUN_ELEVATIONS, HELD_OUT_ELEVATION):
            e = math.radians(elevation)
            to_sun = np.array([math.cos(e), 0.0, math.sin(e)])
            sun.rotation_euler = Vector(-to_sun).to_track_quat("-Z", "Y").to_euler()  # a light shines along −Z
            v, _ = render(os.path.join(tmp, "sun.exr"))
            lit.append(v[hit])
            dirs.append(np.stack([t @ to_sun, b @ to_sun, np.full(len(t), to_sun[2])], -1))
        start = (1.0, 0.0)
        for i in range(NODES):
            mu0 = i / (NODES - 1)
            near = np.abs(mu - mu0) < half
            if mu0 == 1.0:
                near &= mu < 0.9995  # the frame is undefined straight down
            a_node = linear_at(mu[near], albedo[near], mu0)
            ok = near & (albedo > 1e-6)
            fitted = len(SUN_ELEVATIONS)
            d = np.concatenate([v[ok] / albedo[ok] for v in lit[:fitted]])
            locs = np.concatenate([x[ok] for x in dirs[:fitted]])
            m = np.concatenate([mu[ok]] * fitted)
            keep = d > 1e-4 * d.max() if len(d) else d > 0
            # Below 1e-3 the lobe is too faint to fit (or to see): Cycles skips it below 1e-5.
            if a_node < 1e-3 or keep.sum() < 8:
                continue
            fa, fb = fit_ab(m[keep], d[keep], locs[keep], mu0, start)
            start = (fa, fb)
            # The held-out sun at this node's pixels against the node's lobe.
            close = ok & (np.abs(mu - mu0) < 0.1 / (NODES - 1))
            seen = lit[fitted][close] / albedo[close]
            model = ltc(fa, fb, dirs[fitted][close])
            big = seen > 0.05 * seen.max() if len(seen) else seen > 0
            if big.any():
                err = float(np.sqrt(np.mean(((model[big] - seen[big]) / seen[big]) ** 2)))
                errors.append((err, j, i))
            table[j, i] = (fa, fb, a_node)
        print(f"roughness {roughness:.3f}: albedo {table[j, 0, 2]:.4f}..{table[j, -1, 2]:.4f}, "
              f"a {table[j, -1, 0]:.3f}", file=sys.stderr, flush=True)
    return table, errors


def write_rust(table, errors, path):
    errors.sort()
    median, (worst, wj, wi) = errors[len(errors) // 2][0], errors[-1]
    ninety = errors[int(0.9 * len(errors))][0]
    rows = []
    for j in range(NODES):
        cells = ", ".join("[" + ", ".join(str(np.float32(x)) for x in node) + "]" for node in table[j])
        rows.append(f"    // roughness {j}/{NODES - 1}\n    {cells},")
    body = "\n".join(rows)
    text = f"""//! Cycles' sheen lobe as measured by `tools/measure_sheen.py` (do not edit: rerun it).
//!
//! [a, b, albedo] of the linearly transformed cosine at cos θo = i/{NODES - 1} (fastest) and
//! roughness j/{NODES - 1}; zero where the albedo is below 1e-3 (too faint to fit). Against a sun
//! the fit did not see (elevation {HELD_OUT_ELEVATION:g}°), over each node's pixels, the lobe's relative
//! RMS error is {median:.4f} at the median node, {ninety:.4f} at the 90th percentile, and at worst
//! {worst:.4f} (roughness {wj}/{NODES - 1}, cos θo {wi}/{NODES - 1}: a faint, sharply peaked lobe).

/// Nodes per axis.
pub const NODES: usize = {NODES};

/// The table, roughness-major.
#[rustfmt::skip]
pub static SHEEN: [[f32; 3]; NODES * NODES] = [
{body}
];
"""
    with open(path, "w") as f:
        f.write(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="src/material/tables/sheen.rs")
    a = ap.parse_args()
    sheen, world, sun = build_scene()
    with tempfile.TemporaryDirectory() as tmp:
        table, errors = measure(sheen, world, sun, tmp)
    write_rust(table, errors, a.out)
    print(f"wrote {a.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
