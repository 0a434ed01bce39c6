#!/usr/bin/env python3
"""One-factor Blender test scenes: each changes one material or light of a fixed stage.

Run with a Python that has Blender's `bpy` module (the peers venv,
`tools/peers/setup_venv.sh`), from the repository root:

    ~/.cache/myriad-peers/bin/python tools/make_blender_factors.py tests/data/blender/factors \
        [--render tools/peers/cycles_render.py] [--spp 2048] [--only NAME,...]

For every factor it builds the scene with `bpy.data`/`bpy.ops` in an empty Blender file and
writes NAME.glb with Blender's own glTF exporter (what a user's export is: cameras and
punctual lights on, +Y up). With `--render` it also renders NAME.cycles.exr and
NAME.cycles.json with the peers' Cycles script (Blender's importer, then Cycles CPU) at
128×96, `--spp` samples, 8 bounces, seed 12345.

The stage: a grey Lambertian floor and back wall (base 0.5, roughness 1, Specular IOR
Level 0), a 64×32 smooth UV sphere of radius 0.5 standing on the floor, and two one-sided
emissive quads (radiance 6 white above, radiance 4 warm to the left) facing the sphere.
A factor sets the sphere's Principled BSDF (or replaces the lamps by a spot light).
"""

import argparse
import math
import os
import subprocess
import sys

import bpy

RES = (128, 96)

# name: Principled inputs of the sphere (Blender 5.0 socket names); what it isolates.
FACTORS = {
    "metal": ({"Base Color": (0.9, 0.6, 0.3), "Metallic": 1.0, "Roughness": 0.3},
              "F82-tint metal, rough GGX, multiscatter compensation"),
    "plastic": ({"Base Color": (0.6, 0.1, 0.1), "Roughness": 0.35},
                "dielectric specular layer (IOR 1.5, Specular IOR Level 0.5) over diffuse"),
    "specular": ({"Base Color": (0.2, 0.4, 0.2), "Roughness": 0.2, "IOR": 1.45,
                  "Specular IOR Level": 1.0, "Specular Tint": (1.0, 0.5, 0.2)},
                 "KHR_materials_specular: specularFactor, specularColorFactor, KHR_materials_ior"),
    "coat": ({"Base Color": (0.1, 0.3, 0.8), "Roughness": 0.6, "Coat Weight": 1.0,
              "Coat Roughness": 0.05},
             "KHR_materials_clearcoat over a rough dielectric"),
    "glass_smooth": ({"Base Color": (1.0, 1.0, 1.0), "Roughness": 0.0, "Transmission Weight": 1.0},
                     "smooth solid glass, IOR 1.5"),
    "glass_rough": ({"Base Color": (0.9, 0.95, 1.0), "Roughness": 0.3, "IOR": 1.45,
                     "Transmission Weight": 1.0},
                    "rough tinted solid glass"),
    "sheen": ({"Base Color": (0.02, 0.03, 0.08), "Roughness": 0.5, "Specular IOR Level": 0.0, "Sheen Weight": 1.0,
               "Sheen Roughness": 0.6, "Sheen Tint": (1.0, 0.85, 0.7)},
              "KHR_materials_sheen: Cycles' microfiber sheen, nearly alone (a dark diffuse base)"),
    "anisotropic": ({"Base Color": (0.9, 0.9, 0.9), "Metallic": 1.0, "Roughness": 0.35, "Anisotropic": 0.8,
                     "Anisotropic Rotation": 0.1},
                    "KHR_materials_anisotropy: a brushed metal along Blender's default (radial) tangent, turned 36°"),
    "bulb_frosted_02": ({"Base Color": (1.0, 1.0, 1.0), "Roughness": 0.2, "Transmission Weight": 1.0},
                        "a bulb (emissive sphere) inside a solid frosted glass sphere, roughness 0.2"),
    "bulb_frosted_045": ({"Base Color": (1.0, 1.0, 1.0), "Roughness": 0.45, "Transmission Weight": 1.0},
                         "the bulb inside frosted glass of roughness 0.45"),
    "bulb_frosted_08": ({"Base Color": (1.0, 1.0, 1.0), "Roughness": 0.8, "Transmission Weight": 1.0},
                        "the bulb inside frosted glass of roughness 0.8"),
    "bulb_shell": ({"Base Color": (1.0, 1.0, 1.0), "Roughness": 0.45, "Transmission Weight": 1.0},
                   "the bulb inside a hollow frosted shell 1 cm thick (roughness 0.45)"),
    "bulb_clear": ({"Base Color": (1.0, 1.0, 1.0), "Roughness": 0.0, "Transmission Weight": 1.0},
                   "the bulb inside clear glass"),
    "alpha_blend": ({"Base Color": (0.2, 0.8, 0.2), "Roughness": 1.0, "Specular IOR Level": 0.0,
                     "Alpha": 0.4},
                    "alphaMode BLEND as stochastic transparency"),
    "spot": ({"Base Color": (0.8, 0.8, 0.8), "Roughness": 1.0, "Specular IOR Level": 0.0},
             "a spot light alone: Blender's smoothstep blend (size 50°, blend 0.5)"),
}


def principled(name, inputs):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    for key, value in inputs.items():
        bsdf.inputs[key].default_value = (*value, 1.0) if isinstance(value, tuple) else value
    if inputs.get("Alpha", 1.0) < 1.0:
        mat.surface_render_method = "BLENDED"
    return mat


def lambert(name, grey):
    return principled(name, {"Base Color": (grey, grey, grey), "Roughness": 1.0, "Specular IOR Level": 0.0})


def emitter(name, radiance, colour):
    mat = principled(name, {"Base Color": (0.0, 0.0, 0.0), "Specular IOR Level": 0.0, "Roughness": 1.0,
                            "Emission Color": colour, "Emission Strength": radiance})
    mat.use_backface_culling = True  # exported as doubleSided: false, one-sided emission
    return mat


def plane(name, size, location, rotation, material):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    obj.data.materials.append(material)
    return obj


def stage(factor):
    inputs, _ = FACTORS[factor]
    grey = lambert("grey", 0.5)
    plane("floor", 6.0, (0, 0, 0), (0, 0, 0), grey)
    plane("wall", 6.0, (0, 2, 3), (math.pi / 2, 0, 0), grey)  # faces −y, towards the camera
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.5, location=(0, 0, 0.5))
    sphere = bpy.context.active_object
    sphere.name = "sphere"
    bpy.ops.object.shade_smooth()
    sphere.data.materials.append(principled(factor, inputs))
    if factor == "bulb_shell":
        shell = sphere.modifiers.new("shell", "SOLIDIFY")
        shell.thickness, shell.offset = 0.01, -1.0  # inwards: the outer surface stays
    if factor.startswith("bulb_"):
        # The only light: a small emissive sphere (radiance 40) at the glass sphere's centre.
        bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=0.12, location=(0, 0, 0.5))
        bulb = bpy.context.active_object
        bulb.name = "bulb"
        bpy.ops.object.shade_smooth()
        bulb.data.materials.append(emitter("bulb", 40.0, (1.0, 0.9, 0.7)))
    elif factor == "spot":
        bpy.ops.object.light_add(type="SPOT", location=(1.2, -1.2, 2.2))
        spot = bpy.context.active_object
        spot.data.energy = 300.0
        spot.data.spot_size = math.radians(50)
        spot.data.spot_blend = 0.5
        aim(spot, (0, 0, 0.3))
    else:
        # a plane faces +z; turned over it faces down onto the sphere
        plane("lamp_top", 1.0, (0.3, -0.3, 2.4), (math.pi, 0, 0), emitter("lamp_top", 6.0, (1, 1, 1)))
        side = plane("lamp_side", 0.8, (-1.6, -0.6, 1.0), (0, 0, 0), emitter("lamp_side", 4.0, (1.0, 0.7, 0.4)))
        aim(side, (0, 0, 0.5), axis="Z")
    bpy.ops.object.camera_add(location=(0, -3.6, 1.3))
    cam = bpy.context.active_object
    cam.data.lens = 40
    aim(cam, (0, 0, 0.55))
    bpy.context.scene.camera = cam
    render = bpy.context.scene.render
    render.resolution_x, render.resolution_y = RES


def aim(obj, target, axis="-Z"):
    """Turns `obj` so that its local `axis` (−Z for cameras and lights, +Z for a plane's normal) points at `target`."""
    from mathutils import Vector
    direction = Vector(target) - obj.location
    obj.rotation_euler = direction.to_track_quat(axis, "Y").to_euler()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--render", help="path of the peers' cycles_render.py; renders NAME.cycles.exr")
    ap.add_argument("--spp", type=int, default=2048)
    ap.add_argument("--only", help="comma-separated factor names")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    names = a.only.split(",") if a.only else list(FACTORS)
    for name in names:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        stage(name)
        glb = os.path.join(a.out, f"{name}.glb")
        bpy.ops.export_scene.gltf(filepath=os.path.abspath(glb), export_format="GLB", export_cameras=True,
                                  export_lights=True, export_yup=True, export_apply=True)
        print(f"{glb}: {FACTORS[name][1]}", flush=True)
        if a.render:
            exr = os.path.join(a.out, f"{name}.cycles.exr")
            # Cycles' light sampling overestimates a lamp inside rough glass (docs/materials.md):
            # those references are rendered by BSDF rays alone, which Cycles gets right.
            unbiased = ["--no-emitter-sampling"] if name.startswith("bulb_") else []
            subprocess.run([sys.executable, a.render, glb, "--out", exr, "--json", exr[:-4] + ".json",
                            "--res", str(RES[0]), str(RES[1]), "--spp", str(a.spp), "--max-bounces", "8",
                            "--seed", "12345", "--role", "ref", *unbiased], check=True)


if __name__ == "__main__":
    main()
