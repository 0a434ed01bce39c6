#!/usr/bin/env python3
"""One-factor .blend files for the Blender add-on, and what Cycles renders from them.

Run with a Python that has Blender's `bpy` module (the peers venv, `tools/peers/setup_venv.sh`),
from the repository root:

    ~/.cache/myriad-peers/bin/python tools/make_blender_addon_scenes.py tests/data/blender/addon \
        [--spp 2048] [--only NAME,...] [--no-render]

Every scene is the same stage with one thing changed: a grey Lambertian floor and back wall
(base 0.5, Specular IOR Level 0), a smooth UV sphere of radius 0.5 on the floor (grey
Lambert unless the factor is a material), a 128 × 96 camera; the factor is the light (each
Blender light kind and shape, as glTF cannot carry them), the world, emissive meshes,
Principled materials or the camera. Each is saved as NAME.blend (its image files beside it)
and rendered by Cycles (CPU) to NAME.cycles.exr: 128 × 96, `--spp` samples, seed 12345,
8 bounces of every kind, a 1-px box filter, no denoising, adaptive sampling, clamping or
glossy filter; NAME.cycles.json holds the settings and the time. The add-on's test
(tests/it/blender_addon.rs) renders each file with F12 through the add-on at 25 %
(32 × 24, 256 spp) and compares with these.
"""

import argparse
import json
import math
import os
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "blender"))
from myriad_blender.export.images import write_hdr  # noqa: E402

RES = (128, 96)


def lambert(name, colour):
    mat = bpy.data.materials.new(name)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = 1.0
    bsdf.inputs["Specular IOR Level"].default_value = 0.0
    return mat


def principled(name, **inputs):
    mat = bpy.data.materials.new(name)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    for k, v in inputs.items():
        socket = bsdf.inputs[k.replace("_", " ")]
        socket.default_value = (*v, 1.0) if isinstance(v, tuple) and len(v) == 3 else v
    return mat


def add_plane(name, size, location, rotation, material):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location, rotation=rotation)
    obj = bpy.context.object
    obj.name = name
    obj.data.materials.append(material)
    return obj


def add_sphere(location, radius, material, name="sphere"):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=radius, location=location)
    obj = bpy.context.object
    obj.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(material)
    return obj


def light(kind, location, rotation=(0, 0, 0), **data):
    bpy.ops.object.light_add(type=kind, location=location, rotation=rotation)
    obj = bpy.context.object
    for k, v in data.items():
        setattr(obj.data, k, v)
    return obj


def stage(world=None):
    """An empty file with the floor, the back wall, the camera and (by default) a black world."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    grey = lambert("grey", (0.5, 0.5, 0.5))
    add_plane("floor", 8, (0, 0, 0), (0, 0, 0), grey)
    add_plane("wall", 8, (0, 2, 2), (math.pi / 2, 0, 0), grey)
    bpy.ops.object.camera_add(location=(0, -5.5, 1.6), rotation=(math.radians(82), 0, 0))
    scene.camera = bpy.context.object
    scene.world = bpy.data.worlds.new("world")
    bg = scene.world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (*(world or (0, 0, 0)), 1.0)
    return scene, grey


def grey_sphere(grey):
    add_sphere((0, 0, 0.5), 0.5, grey)


def sky_image(folder):
    """A small equirectangular sky: a bright warm sun blob, a blue gradient, a dark ground."""
    h, w = 32, 64
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    theta = v[:, None] * math.pi
    phi = (0.5 - u[None, :]) * 2 * math.pi
    up = np.broadcast_to(np.cos(theta), (h, w))
    rgb = np.zeros((h, w, 3), dtype=np.float32)
    rgb[..., 0] = 0.2 + 0.3 * np.clip(up, 0, 1)
    rgb[..., 1] = 0.3 + 0.4 * np.clip(up, 0, 1)
    rgb[..., 2] = 0.5 + 0.6 * np.clip(up, 0, 1)
    rgb[up < 0] = (0.05, 0.04, 0.03)
    sun = np.exp(-((theta - 0.9) ** 2 + (phi - 0.8) ** 2) / 0.02)
    rgb += sun[..., None] * np.array([20.0, 16.0, 10.0])
    path = os.path.join(folder, "sky.hdr")
    write_hdr(path, rgb)
    return path


def build(name, folder):
    """Builds scene `name`; what it isolates."""
    if name.startswith("area_"):
        scene, grey = stage()
        grey_sphere(grey)
        shape = name[len("area_"):].upper()
        sizes = {"SQUARE": (0.8, 0.8), "RECTANGLE": (1.2, 0.4), "DISK": (0.9, 0.9), "ELLIPSE": (1.2, 0.5)}
        spread = {"RECTANGLE": math.radians(90)}.get(shape, math.pi)
        light("AREA", (0.6, -0.8, 2.4), (math.radians(20), math.radians(15), 0), energy=150.0, shape=shape,
              size=sizes[shape][0], size_y=sizes[shape][1], spread=spread, color=(1.0, 0.9, 0.8))
        return f"an area light, {shape.lower()}" + (", spread 90°" if spread < math.pi else "")
    if name in {"point_soft", "point_sphere"}:
        scene, grey = stage()
        grey_sphere(grey)
        light("POINT", (0.7, -0.7, 1.3), energy=80.0, shadow_soft_size=0.3, use_soft_falloff=(name == "point_soft"))
        return "a point light of radius 0.3, soft falloff " + ("on (a facing disk)" if name == "point_soft" else "off (a sphere)")
    if name == "spot_radius":
        scene, grey = stage()
        grey_sphere(grey)
        light("SPOT", (0.0, -1.2, 2.2), (math.radians(30), 0, 0), energy=300.0, shadow_soft_size=0.15,
              spot_size=math.radians(60), spot_blend=0.3)
        return "a spot of radius 0.15, size 60°, blend 0.3"
    if name == "lamp_in_glass":
        scene, grey = stage()
        add_sphere((0, 0, 0.5), 0.5, principled("glass", Base_Color=(1.0, 1.0, 1.0), Roughness=0.0, IOR=1.45,
                                                 Transmission_Weight=1.0), name="globe")
        light("POINT", (0.05, -0.05, 0.55), energy=40.0, shadow_soft_size=0.1, color=(1.0, 0.85, 0.6))
        return "a point light of radius 0.1 (soft falloff) inside a smooth glass ball"
    if name == "sun_angle":
        scene, grey = stage()
        grey_sphere(grey)
        light("SUN", (0, 0, 5), (math.radians(40), math.radians(-20), 0), energy=2.0, angle=math.radians(15))
        return "a sun of 2 W/m² and angle 15°"
    if name == "world_color":
        scene, grey = stage(world=(0.3, 0.4, 0.6))
        grey_sphere(grey)
        return "a uniform world colour only"
    if name == "world_hdri":
        scene, grey = stage()
        grey_sphere(grey)
        tree = scene.world.node_tree
        env = tree.nodes.new("ShaderNodeTexEnvironment")
        env.image = bpy.data.images.load(sky_image(folder))
        env.image.filepath = "//sky.hdr"
        mapping = tree.nodes.new("ShaderNodeMapping")
        coords = tree.nodes.new("ShaderNodeTexCoord")
        mapping.inputs["Rotation"].default_value = (0, 0, math.radians(30))
        tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
        tree.links.new(env.outputs["Color"], tree.nodes["Background"].inputs["Color"])
        tree.nodes["Background"].inputs["Strength"].default_value = 1.5
        return "an HDR Environment Texture × 1.5, rotated 30° by a Mapping node"
    if name == "emissive_mesh":
        scene, grey = stage()
        grey_sphere(grey)
        bpy.ops.mesh.primitive_cube_add(size=0.4, location=(-0.9, -0.4, 0.4))
        cube = bpy.context.object
        glow = bpy.data.materials.new("glow")
        nodes = glow.node_tree.nodes
        nodes.remove(nodes["Principled BSDF"])
        emit = nodes.new("ShaderNodeEmission")
        emit.inputs["Color"].default_value = (1.0, 0.6, 0.3, 1.0)
        emit.inputs["Strength"].default_value = 8.0
        glow.node_tree.links.new(emit.outputs["Emission"], nodes["Material Output"].inputs["Surface"])
        cube.data.materials.append(glow)
        panel = add_plane("panel", 0.6, (0.9, -0.3, 1.2), (math.radians(60), 0, math.radians(-30)),
                          principled("panel", Base_Color=(0.0, 0.0, 0.0), Emission_Color=(0.6, 0.8, 1.0),
                                     Emission_Strength=6.0))
        panel.name = "panel"
        return "an Emission-shader cube and a Principled emissive plane (emitting from both faces)"
    if name == "principled":
        scene, grey = stage()
        add_sphere((-1.1, 0, 0.5), 0.5, principled("metal", Base_Color=(0.9, 0.6, 0.3), Metallic=1.0, Roughness=0.3))
        add_sphere((0, 0, 0.5), 0.5, principled("plastic", Base_Color=(0.6, 0.1, 0.1), Roughness=0.3,
                                                 Specular_IOR_Level=0.8, Specular_Tint=(1.0, 0.7, 0.5)))
        add_sphere((1.1, 0, 0.5), 0.5, principled("coat", Base_Color=(0.1, 0.3, 0.8), Roughness=0.6,
                                                   Coat_Weight=1.0, Coat_Roughness=0.1))
        add_sphere((0.55, -0.9, 0.3), 0.3, principled("glass", Base_Color=(0.95, 0.95, 1.0), Roughness=0.1, IOR=1.45,
                                                       Transmission_Weight=1.0), name="glass")
        light("AREA", (0, -1.5, 2.5), (math.radians(40), 0, 0), energy=300.0, size=1.5, size_y=0.6, shape="RECTANGLE")
        return "metal, plastic with specular tint, coat, rough glass: Principled BSDFs under an area light"
    if name == "sheen_anisotropic":
        scene, grey = stage()
        add_sphere((-0.6, 0, 0.5), 0.5, principled("velvet", Base_Color=(0.3, 0.1, 0.2), Roughness=0.6,
                                                    Sheen_Weight=1.0, Sheen_Roughness=0.5,
                                                    Sheen_Tint=(1.0, 0.6, 0.8)))
        add_sphere((0.6, 0, 0.5), 0.5, principled("brushed", Base_Color=(0.9, 0.85, 0.8), Metallic=1.0, Roughness=0.4,
                                                   Anisotropic=0.6, Anisotropic_Rotation=0.15), name="brushed")
        light("AREA", (0, -1.5, 2.5), (math.radians(40), 0, 0), energy=300.0, size=1.5, size_y=0.6, shape="RECTANGLE")
        return "a sheen (velvet) and an anisotropic brushed metal under an area light"
    if name == "camera":
        scene, grey = stage()
        grey_sphere(grey)
        add_sphere((0.8, 1.0, 0.3), 0.3, grey, name="far sphere")
        light("AREA", (0, -1.0, 2.5), (math.radians(25), 0, 0), energy=250.0, size=1.5)
        cam = scene.camera.data
        cam.sensor_fit = "VERTICAL"
        cam.sensor_height = 20.0
        cam.shift_x, cam.shift_y = 0.08, -0.05
        cam.dof.use_dof = True
        cam.dof.aperture_fstop = 1.4
        cam.dof.focus_object = bpy.data.objects["sphere"]
        return "vertical sensor fit, lens shift, depth of field focused on the sphere at f/1.4"
    raise SystemExit(f"no scene named {name}")


SCENES = [
    "area_square", "area_rectangle", "area_disk", "area_ellipse", "point_soft", "point_sphere", "spot_radius",
    "lamp_in_glass",
    "sun_angle", "world_color", "world_hdri", "emissive_mesh", "principled", "sheen_anisotropic", "camera",
]  # fmt: skip


def cycles_settings(scene, spp):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.seed = 12345
    c.use_denoising = False
    c.use_adaptive_sampling = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 8
    c.transparent_max_bounces = 8
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    scene.render.resolution_x, scene.render.resolution_y = RES
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("--spp", type=int, default=2048)
    ap.add_argument("--only", default="")
    ap.add_argument("--no-render", action="store_true")
    args = ap.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
    folder = os.path.abspath(args.folder)
    os.makedirs(folder, exist_ok=True)
    names = args.only.split(",") if args.only else SCENES
    for name in names:
        what = build(name, folder)
        scene = bpy.context.scene
        cycles_settings(scene, args.spp)
        blend = os.path.join(folder, f"{name}.blend")
        bpy.context.preferences.filepaths.save_version = 0
        bpy.ops.wm.save_as_mainfile(filepath=blend, relative_remap=True)
        print(f"{name}: {what}", flush=True)
        if args.no_render:
            continue
        scene.render.filepath = os.path.join(folder, f"{name}.cycles.exr")
        start, cpu = time.time(), time.process_time()
        bpy.ops.render.render(write_still=True)
        info = {"scene": f"{name}.blend", "what": what, "blender": bpy.app.version_string, "resolution": RES,
                "spp": args.spp, "seed": 12345, "bounces": 8, "filter": "box 1 px", "denoising": False,
                "clamp": 0, "filter_glossy": 0, "t_render_s": round(time.time() - start, 1),
                "cpu_render_s": round(time.process_time() - cpu, 1)}
        with open(os.path.join(folder, f"{name}.cycles.json"), "w") as f:
            json.dump(info, f, indent=1)
        print(f"  Cycles: {info['t_render_s']} s", flush=True)


if __name__ == "__main__":
    main()
