#!/usr/bin/env python3
"""F12 through the Blender add-on on a large scene: how long from F12 to the first image, and
the export's share of a render.

    ~/.cache/myriad-peers/bin/python tools/blender_addon_bench.py [--spp 64] [--res 320x240] [--unique-meshes]

Builds (in Blender's `bpy` module) a room of about 10⁵ triangles (subdivided spheres and
boxes, Principled materials) lit by 10³ lights (600 point lights of radius 0.05, 300 area
lights, 100 spots), then presses F12 with the add-on and prints the export time, the time
to the first image, the whole render and the export's share, from the add-on's own timings
(MYRIAD_BLENDER_KEEP). MYRIAD_BIN names the myriad executable (default target/release/myriad).
"""

import argparse
import math
import os
import random
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "blender"))

import bpy  # noqa: E402

import myriad_blender  # noqa: E402


def build(unique):
    """The scene, made with bpy.data: linked duplicates of a few meshes (as common in real
    files), or with `unique` a mesh of its own for every object."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    rng = random.Random(7)
    mats = []
    for i in range(12):
        m = bpy.data.materials.new(f"m{i}")
        b = m.node_tree.nodes["Principled BSDF"]
        b.inputs["Base Color"].default_value = (rng.random(), rng.random(), rng.random(), 1)
        b.inputs["Roughness"].default_value = rng.uniform(0.1, 0.9)
        b.inputs["Metallic"].default_value = 1.0 if i % 4 == 0 else 0.0
        mats.append(m)

    bpy.ops.mesh.primitive_plane_add(size=40)
    bpy.context.object.data.materials.append(mats[1])
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.8)
    sphere = bpy.context.object
    sphere.data.materials.append(mats[0])
    bpy.ops.mesh.primitive_cube_add(size=0.3)
    cube = bpy.context.object
    cube.data.materials.append(mats[2])
    triangles = 2
    for i in range(48):
        obj = bpy.data.objects.new(f"sphere{i}", sphere.data.copy() if unique else sphere.data)
        obj.location = ((i % 8 - 3.5) * 4, (i // 8 - 2.5) * 4, 0.8)
        scene.collection.objects.link(obj)
        triangles += 48 * 24 * 2
    for i in range(2000):
        obj = bpy.data.objects.new(f"cube{i}", cube.data.copy() if unique else cube.data)
        obj.location = (rng.uniform(-18, 18), rng.uniform(-18, 18), 0.2)
        obj.scale = (rng.uniform(0.3, 1.3),) * 3
        scene.collection.objects.link(obj)
        triangles += 12
    kinds = [("POINT", 600), ("AREA", 300), ("SPOT", 100)]
    for kind, count in kinds:
        for i in range(count):
            data = bpy.data.lights.new(f"{kind}{i}", kind)
            data.energy = rng.uniform(5, 300)
            if kind == "POINT":
                data.shadow_soft_size = 0.05
            if kind == "AREA":
                data.size = 0.5
            obj = bpy.data.objects.new(f"{kind}{i}", data)
            obj.location = (rng.uniform(-18, 18), rng.uniform(-18, 18), rng.uniform(2, 5))
            scene.collection.objects.link(obj)
    bpy.ops.object.camera_add(location=(0, -24, 10), rotation=(math.radians(65), 0, 0))
    scene.camera = bpy.context.object
    return scene, triangles, sum(c for _, c in kinds)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", default="320x240")
    ap.add_argument("--unique-meshes", action="store_true", help="a mesh of its own for every object")
    args = ap.parse_args()
    os.environ.setdefault("MYRIAD_BIN", os.path.join(ROOT, "target", "release", "myriad"))
    myriad_blender.register()
    t = time.perf_counter()
    scene, triangles, lights = build(args.unique_meshes)
    print(f"built {triangles} triangles (about), {lights} lights in {time.perf_counter() - t:.1f} s")
    scene.render.engine = "MYRIAD"
    w, h = (int(x) for x in args.res.split("x"))
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    scene.myriad.samples = args.spp
    with tempfile.TemporaryDirectory() as keep:
        os.environ["MYRIAD_BLENDER_KEEP"] = keep
        start = time.perf_counter()
        bpy.ops.render.render()
        total = time.perf_counter() - start
        timings = open(next(os.path.join(r, f) for r, _, fs in os.walk(keep) for f in fs if f == "timings.txt")).read()
    fields = dict(part.strip().rsplit(" ", 2)[0:2] for part in timings.strip().split(","))
    export = float(fields["export"])
    first = float(fields["first image"])
    print(f"F12 to the end: {total:.2f} s; export {export:.2f} s ({100 * export / total:.0f} %), "
          f"first image {export + first:.2f} s after F12 ({first:.2f} s after myriad started)")


if __name__ == "__main__":
    main()
