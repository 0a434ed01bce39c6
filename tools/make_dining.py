#!/usr/bin/env python3
"""A dining room lit by bulbs in glass: the interior issue 45 measures path guiding and the
connections through glass on (its own held-back scene is not in the repository).

Run with a Python that has Blender's `bpy` module (the peers venv,
`tools/peers/setup_venv.sh`), from the repository root:

    ~/.cache/myriad-peers/bin/python tools/make_dining.py tests/data/blender/dining.glb

It builds the room with `bpy` in an empty Blender file and writes it with Blender's own glTF
exporter (cameras and punctual lights on, +Y up): a 5 × 4 × 2.8 m room (white walls and
ceiling, a wooden floor, roughness 0.6), a table (dark wood, coated) with six chairs
(coated paint), a chandelier of 24 bulbs (emissive spheres of radius 3 cm, radiance 60)
each inside a solid frosted glass sphere (radius 7 cm, roughness 0.45) on a ring over the
table, two clear glass globes (roughness 0) with a bulb inside on a sideboard, and six
clear glasses and a carafe (solid glass, roughness 0) on the table. The camera looks at the
table from a corner at 320 × 240.
"""

import math
import os
import sys

import bpy

RES = (320, 240)


def principled(name, **inputs):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    for key, value in inputs.items():
        socket = bsdf.inputs[key.replace("_", " ")]
        socket.default_value = (*value, 1.0) if isinstance(value, tuple) else value
    return mat


def emitter(name, radiance, colour):
    return principled(name, Base_Color=(0.0, 0.0, 0.0), Specular_IOR_Level=0.0, Roughness=1.0,
                      Emission_Color=colour, Emission_Strength=radiance)


def box(name, size, location, material):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=location)
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = size
    obj.data.materials.append(material)
    return obj


def sphere(name, radius, location, material, segments=32, rings=16):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings, radius=radius, location=location)
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(material)
    return obj


def cylinder(name, radius, depth, location, material):
    bpy.ops.mesh.primitive_cylinder_add(vertices=32, radius=radius, depth=depth, location=location)
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(material)
    return obj


def room():
    white = principled("wall", Base_Color=(0.8, 0.78, 0.75), Roughness=1.0, Specular_IOR_Level=0.0)
    floor = principled("floor", Base_Color=(0.35, 0.22, 0.12), Roughness=0.6)
    table_wood = principled("table", Base_Color=(0.15, 0.08, 0.04), Roughness=0.5, Coat_Weight=1.0,
                            Coat_Roughness=0.05)
    paint = principled("chair_paint", Base_Color=(0.5, 0.1, 0.08), Roughness=0.4, Coat_Weight=1.0,
                       Coat_Roughness=0.1)
    frosted = principled("frosted_glass", Base_Color=(1.0, 1.0, 1.0), Roughness=0.45, Transmission_Weight=1.0)
    clear = principled("clear_glass", Base_Color=(1.0, 1.0, 1.0), Roughness=0.0, Transmission_Weight=1.0)
    bulb = emitter("bulb", 60.0, (1.0, 0.85, 0.6))

    # The room: floor, ceiling and four walls (boxes 10 cm thick), 5 × 4 × 2.8 m.
    box("floor", (5.0, 4.0, 0.1), (0, 0, -0.05), floor)
    box("ceiling", (5.0, 4.0, 0.1), (0, 0, 2.85), white)
    for name, size, loc in [("wall_n", (5.0, 0.1, 2.8), (0, 2.05, 1.4)), ("wall_s", (5.0, 0.1, 2.8), (0, -2.05, 1.4)),
                            ("wall_e", (0.1, 4.0, 2.8), (2.55, 0, 1.4)), ("wall_w", (0.1, 4.0, 2.8), (-2.55, 0, 1.4))]:
        box(name, size, loc, white)

    # The table and six chairs.
    box("table_top", (2.0, 1.0, 0.05), (0, 0, 0.75), table_wood)
    for i, (x, y) in enumerate([(-0.9, -0.4), (0.9, -0.4), (-0.9, 0.4), (0.9, 0.4)]):
        box(f"table_leg_{i}", (0.06, 0.06, 0.72), (x, y, 0.36), table_wood)
    for i, (x, y, back) in enumerate([(-0.6, -0.75, -1), (0.0, -0.75, -1), (0.6, -0.75, -1),
                                      (-0.6, 0.75, 1), (0.0, 0.75, 1), (0.6, 0.75, 1)]):
        box(f"chair_seat_{i}", (0.42, 0.42, 0.04), (x, y, 0.45), paint)
        box(f"chair_back_{i}", (0.42, 0.04, 0.5), (x, y + back * 0.19, 0.72), paint)
        for j, (dx, dy) in enumerate([(-0.18, -0.18), (0.18, -0.18), (-0.18, 0.18), (0.18, 0.18)]):
            box(f"chair_leg_{i}_{j}", (0.03, 0.03, 0.43), (x + dx, y + dy, 0.215), paint)

    # The chandelier: 24 bulbs in frosted glass spheres on two rings over the table.
    for i in range(24):
        ring, k = (0.7, i) if i < 16 else (0.35, i - 16)
        n = 16 if i < 16 else 8
        a = 2 * math.pi * (k + 0.5 * (i >= 16)) / n
        p = (ring * math.cos(a), ring * 0.6 * math.sin(a), 1.95 if i < 16 else 2.1)
        sphere(f"shade_{i}", 0.07, p, frosted)
        sphere(f"bulb_{i}", 0.03, p, bulb, segments=16, rings=8)

    # A sideboard with two clear globes, a bulb in each.
    box("sideboard", (1.6, 0.45, 0.9), (0, 1.75, 0.45), table_wood)
    for i, x in enumerate([-0.5, 0.5]):
        p = (x, 1.75, 1.1)
        sphere(f"globe_{i}", 0.18, p, clear, segments=48, rings=24)
        sphere(f"globe_bulb_{i}", 0.04, p, bulb, segments=16, rings=8)

    # Six clear glasses and a carafe on the table (solid glass).
    for i, (x, y) in enumerate([(-0.6, -0.3), (0.0, -0.3), (0.6, -0.3), (-0.6, 0.3), (0.0, 0.3), (0.6, 0.3)]):
        cylinder(f"glass_{i}", 0.035, 0.12, (x, y, 0.835), clear)
    cylinder("carafe", 0.07, 0.28, (0.25, 0.0, 0.915), clear)

    bpy.ops.object.camera_add(location=(2.2, -1.8, 1.6))
    cam = bpy.context.active_object
    cam.data.lens = 22
    from mathutils import Vector
    cam.rotation_euler = (Vector((0, 0.2, 0.9)) - cam.location).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = cam
    render = bpy.context.scene.render
    render.resolution_x, render.resolution_y = RES


def main():
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    room()
    out = os.path.abspath(sys.argv[1])
    bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_cameras=True, export_lights=True,
                              export_yup=True, export_apply=True)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
