"""The Blender add-on as a user runs it, in Blender's `bpy` module (tests/it/blender_addon.rs
runs this with the peers venv's Python and checks what it writes).

    python blender/tests/addon_tests.py SCENES_DIR OUT_DIR

with MYRIAD_BIN naming the myriad executable. For every SCENES_DIR/NAME.blend it selects the
myriad engine and presses F12 (`bpy.ops.render.render(write_still=True)`) at 25 % with 256
spp, keeping the exported scene in OUT_DIR/keep/ (MYRIAD_BLENDER_KEEP) and saving the Render
Result to OUT_DIR/NAME.exr; one file is also saved as a multi-layer EXR with its passes, and
exported with File › Export › myriad scene. Then the bad inputs: a missing or wrong
executable, a scene without a camera, materials and lights myriad cannot render, and a
render stopped half-way. Everything it saw goes to OUT_DIR/summary.json.
"""

import glob
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import bpy  # noqa: E402

import myriad_blender  # noqa: E402
from myriad_blender.export import ExportError, export_scene  # noqa: E402
from myriad_blender.runner import Render  # noqa: E402


def render(path):
    """F12; the error Blender reports, or None."""
    try:
        bpy.ops.render.render(write_still=True)
        return None
    except RuntimeError as e:
        return str(e)


def exported_warnings(scene):
    """What exporting `scene` warns about, or the error it stops with."""
    with tempfile.TemporaryDirectory() as folder:
        try:
            return export_scene(bpy.context.evaluated_depsgraph_get(), folder, scene.myriad).warnings
        except ExportError as e:
            return [f"error: {e}"]


def composite(scene, out, name, wire):
    """Renders through a compositor node tree that `wire(tree, render_layers, output)` sets up;
    the error, the Render Layers node's outputs, and the file it saved."""
    tree = bpy.data.node_groups.new("myriad test", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    scene.compositing_node_group = tree
    layers = tree.nodes.new("CompositorNodeRLayers")
    output = tree.nodes.new("NodeGroupOutput")
    wire(tree, layers, output)
    scene.render.filepath = os.path.join(out, name)
    error = render(scene)
    scene.compositing_node_group = None
    return error, [o.name for o in layers.outputs if o.enabled], scene.render.filepath


def passes(scene, out, name):
    """The Denoising Albedo pass saved alone, and the image through Blender's Denoise node
    (Image, Albedo and Normal from myriad's passes)."""

    def albedo(tree, layers, output):
        tree.links.new(layers.outputs["Denoising Albedo"], output.inputs[0])

    def denoised(tree, layers, output):
        node = tree.nodes.new("CompositorNodeDenoise")
        tree.links.new(layers.outputs["Image"], node.inputs["Image"])
        tree.links.new(layers.outputs["Denoising Albedo"], node.inputs["Albedo"])
        tree.links.new(layers.outputs["Denoising Normal"], node.inputs["Normal"])
        tree.links.new(node.outputs["Image"], output.inputs[0])

    a_error, outputs, a_file = composite(scene, out, f"{name}.albedo.exr", albedo)
    d_error, _, d_file = composite(scene, out, f"{name}.denoised.exr", denoised)
    return {"errors": [a_error, d_error], "outputs": outputs, "albedo": a_file, "denoised": d_file}


def bad_inputs(first_blend, out):
    """The errors and warnings a user gets for input myriad cannot render."""
    found = {}
    bpy.ops.wm.open_mainfile(filepath=first_blend)
    scene = bpy.context.scene
    scene.render.engine = "MYRIAD"
    scene.render.resolution_percentage = 10
    scene.myriad.samples = 4
    scene.render.filepath = os.path.join(out, "bad.exr")
    for name, binary in [("missing_binary", "/nonexistent/myriad"), ("wrong_binary", "/bin/true")]:
        scene.myriad.binary = binary
        found[name] = render(scene)
    scene.myriad.binary = ""
    # A material and a light myriad cannot render as they are.
    mat = bpy.data.materials.new("skin")
    nodes = mat.node_tree.nodes
    principled = nodes["Principled BSDF"]
    principled.inputs["Subsurface Weight"].default_value = 0.5
    mix = nodes.new("ShaderNodeMixShader")
    mix.name = "Blend Mix"
    mat.node_tree.links.new(principled.outputs["BSDF"], mix.inputs[1])
    mat.node_tree.links.new(mix.outputs["Shader"], nodes["Material Output"].inputs["Surface"])
    bpy.data.objects["sphere"].data.materials[0] = mat
    portal = bpy.data.lights.new("window portal", "AREA")
    portal.cycles.is_portal = True
    obj = bpy.data.objects.new("window portal", portal)
    scene.collection.objects.link(obj)
    found["warnings"] = exported_warnings(scene)
    # Without a camera: the export says what to do.
    scene.camera = None
    found["no_camera"] = exported_warnings(scene)
    return found


def stopped_render(keep_dir, out):
    """A long render stopped after a second: how long the stop took, its status, and whether
    it left an image."""
    ron = sorted(glob.glob(os.path.join(keep_dir, "*", "scene.ron")))[0]
    image = os.path.join(out, "stopped.exr")
    run = Render(os.environ["MYRIAD_BIN"], ["render", ron, "-o", image, "--spp", "1000000", "--no-png"])
    time.sleep(1.5)
    first = run.poll()
    start = time.perf_counter()
    run.stop()
    code, _ = run.finish()
    return {"seconds": time.perf_counter() - start, "status": code, "image_left": os.path.exists(image),
            "saw_an_image": first is not None}


def main():
    scenes_dir, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    keep = os.path.join(out, "keep")
    os.environ["MYRIAD_BLENDER_KEEP"] = keep
    myriad_blender.register()
    summary = {"scenes": {}}
    blends = sorted(glob.glob(os.path.join(scenes_dir, "*.blend")))
    for blend in blends:
        name = os.path.splitext(os.path.basename(blend))[0]
        bpy.ops.wm.open_mainfile(filepath=blend)
        scene = bpy.context.scene
        scene.render.engine = "MYRIAD"
        scene.render.resolution_percentage = 25
        scene.myriad.samples = 256
        scene.myriad.max_depth = 9
        scene.myriad.seed = 5
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        scene.render.filepath = os.path.join(out, f"{name}.exr")
        start = time.perf_counter()
        error = render(scene)
        summary["scenes"][name] = {"error": error, "seconds": time.perf_counter() - start,
                                   "keep": os.path.join(keep, f"{name}-{scene.name}-{scene.frame_current}")}
        if name == os.path.splitext(os.path.basename(blends[0]))[0]:
            summary["passes"] = passes(scene, out, name)
            target = os.path.join(out, "exported", f"{name}.ron")
            os.makedirs(os.path.dirname(target), exist_ok=True)
            summary["export_operator"] = sorted(bpy.ops.export_scene.myriad(filepath=target))
            # Clamping, guiding and caustics set in the panel reach the scene file.
            scene.myriad.clamp_indirect = 10.0
            scene.myriad.guiding = True
            scene.myriad.caustics = False
            clamped = os.path.join(out, "exported", f"{name}-clamped.ron")
            bpy.ops.export_scene.myriad(filepath=clamped)
            with open(clamped, encoding="utf-8") as f:
                summary["clamped_render_block"] = next((line.strip() for line in f if "render:" in line), "")
            scene.myriad.clamp_indirect = 0.0
            scene.myriad.guiding = False
            scene.myriad.caustics = True
    summary["bad_inputs"] = bad_inputs(blends[0], out)
    summary["stopped"] = stopped_render(keep, out)
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    myriad_blender.unregister()


if __name__ == "__main__":
    main()
