#!/usr/bin/env python3
"""One scene in the forms real tools write it: Blender's exporter plain, with Draco mesh
compression and with WebP images; gltfpack's quantised (KHR_mesh_quantization) and
meshopt-compressed (EXT_meshopt_compression) repacks of the plain file.

Run with a Python that has Blender's `bpy` module (the peers venv,
`tools/peers/setup_venv.sh`), from the repository root, with npm's `npx` on the PATH for
gltfpack (fetched on first use):

    ~/.cache/myriad-peers/bin/python tools/make_gltf_variants.py tests/data/gltf-variants

The scene is make_blender_factors.py's stage (grey floor and wall, a smooth UV sphere, two
emissive quads) with the sphere's base colour an 64×64 image texture (a painted checker,
packed into the file) and a point light, so that every variant carries smooth normals,
texture coordinates, an image and emitters. tests/it/gltf_variants.rs renders them all.
"""

import os
import subprocess
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_blender_factors as factors  # noqa: E402


def textured_sphere():
    img = bpy.data.images.new("checker", 64, 64)
    pixels = []
    for y in range(64):
        for x in range(64):
            on = ((x // 8) + (y // 8)) % 2 == 0
            pixels += [0.8, 0.3, 0.1, 1.0] if on else [0.1, 0.5, 0.8, 1.0]
    img.pixels = pixels
    img.pack()
    mat = bpy.data.objects["sphere"].data.materials[0]
    tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = img
    mat.node_tree.links.new(tex.outputs["Color"], mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"])


def export(path, **options):
    bpy.ops.export_scene.gltf(filepath=os.path.abspath(path), export_format="GLB", export_cameras=True,
                              export_lights=True, export_yup=True, **options)
    print(path, flush=True)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    factors.stage("plastic")
    textured_sphere()
    bpy.ops.object.light_add(type="POINT", location=(1.0, -1.5, 1.8))
    bpy.context.active_object.data.energy = 60.0
    plain = os.path.join(out, "plain.glb")
    export(plain)
    export(os.path.join(out, "draco.glb"), export_draco_mesh_compression_enable=True)
    # Lossless-quality WebP: the same texels as the PNG, so the same picture.
    export(os.path.join(out, "webp.glb"), export_image_format="WEBP", export_image_quality=100)
    # gltfpack: quantised attributes by default; -cc adds meshopt compression with its
    # filters (octahedral normals, exponent-mantissa floats). -kn keeps the
    # node names and -km the materials as they are, so the scene stays the same scene.
    for name, flags in [("quantized.glb", []), ("meshopt.glb", ["-cc"])]:
        target = os.path.join(out, name)
        subprocess.run(["npx", "--yes", "gltfpack", "-i", plain, "-o", target, "-kn", "-km", *flags], check=True)
        print(target, flush=True)


main()
