"""The render engine: F12 with myriad.

`render()` exports the evaluated scene (export/), runs `myriad render` on it and fills the
Render Result after every pass from myriad's display stream: Combined, and Denoising Albedo
and Denoising Normal (so that Blender's Denoise node, OIDN, works on a myriad render as on a
Cycles one), and Depth where the view layer asks for it. Progress goes to Blender's status
bar, Esc ends myriad at once, and every error reaches the user as a Blender report, never as
a traceback. It works the same in the UI, with `blender -b file.blend -E MYRIAD -f 1`, and in
the `bpy` module.
"""

import os
import shutil
import tempfile
import time

import bpy
import numpy as np

from .export import ExportError, export_scene
from .runner import Render, RunError, check_binary, find_binary

# Environment variable naming a folder to keep each render's exported scene and image in
# (for debugging and for the add-on's tests); otherwise they go to a temporary folder.
KEEP_ENV = "MYRIAD_BLENDER_KEEP"

# Passes beside Combined: (name, channels, channel ids, kind, myriad's channels).
PASSES = [
    ("Denoising Albedo", 3, "RGB", "COLOR", ("albedo.R", "albedo.G", "albedo.B")),
    ("Denoising Normal", 3, "XYZ", "VECTOR", ("N.X", "N.Y", "N.Z")),
    ("Depth", 1, "Z", "VALUE", ("Z",)),
]


def _wanted(view_layer, name):
    return name != "Depth" or view_layer.use_pass_z


class MyriadRenderEngine(bpy.types.RenderEngine):
    """myriad as a Blender render engine."""

    bl_idname = "MYRIAD"
    bl_label = "myriad"
    bl_use_preview = False
    bl_use_postprocess = True
    bl_use_eevee_viewport = True

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        for name, channels, ids, kind, _ in PASSES:
            if _wanted(renderlayer, name):
                self.register_pass(scene, renderlayer, name, channels, ids, kind)

    def render(self, depsgraph):
        try:
            self._render(depsgraph)
        except (ExportError, RunError) as e:
            self.report({"ERROR"}, f"myriad: {e}")
        except Exception as e:  # noqa: BLE001 - a bug of the add-on: a report, not a traceback
            self.report({"ERROR"}, f"myriad add-on failed ({type(e).__name__}: {e}); please report this")

    def _render(self, depsgraph):
        scene = depsgraph.scene
        settings = scene.myriad
        binary = find_binary(bpy.path.abspath(settings.binary) if settings.binary else "")
        check_binary(binary)
        keep = os.environ.get(KEEP_ENV)
        folder = _folder(keep, scene)
        try:
            self._export_and_run(depsgraph, settings, binary, folder)
        finally:
            if not keep:
                shutil.rmtree(folder, ignore_errors=True)

    def _export_and_run(self, depsgraph, settings, binary, folder):
        self.update_stats("", "myriad: exporting the scene")
        export = export_scene(depsgraph, folder, settings)
        for w in export.warnings:
            self.report({"WARNING"}, f"myriad: {w}")
        if self.test_break():
            return
        width, height = export.size
        budget = ["--time", f"{settings.time:g}"] if settings.time > 0 else ["--spp", str(settings.samples)]
        args = [
            "render", export.ron, "-o", os.path.join(folder, "render.exr"), "--no-png",
            "--aov", "albedo,normal,depth", "--resolution", f"{width}x{height}",
            "--sampler", settings.sampler, "--max-depth", str(settings.max_depth), "--seed", str(settings.seed),
            *budget,
        ]  # fmt: skip
        layer = depsgraph.view_layer
        for name, channels, ids, _, _ in PASSES:
            if _wanted(layer, name):
                self.add_pass(name, channels, ids, layer=layer.name)
        result = self.begin_result(0, 0, width, height, layer=layer.name)
        run = Render(binary, args)
        started = time.perf_counter()
        first = None
        try:
            while run.running():
                if self.test_break():
                    run.stop()
                    self.end_result(result, cancel=True)
                    return
                frame = run.poll()
                if frame is not None:
                    first = first or time.perf_counter() - started
                    self._fill(result, frame)
                    self.update_result(result)
                self.update_progress(run.progress)
                self.update_stats("", f"myriad: {100 * run.progress:.0f} %, {time.perf_counter() - started:.1f} s")
                time.sleep(0.05)
        except BaseException:
            run.stop()
            raise
        code, frame = run.finish()
        for w in run.warnings:
            self.report({"WARNING"}, f"myriad: {w}")
        if code != 0:
            self.end_result(result, cancel=True)
            reason = "; ".join(run.errors) or f"it exited with status {code}"
            raise RunError(f"the render failed: {reason}")
        if frame is not None:
            self._fill(result, frame)
        self.end_result(result)
        self.update_progress(1.0)
        self.update_stats("", f"myriad: done in {time.perf_counter() - started:.1f} s (export {export.seconds:.2f} s)")
        if os.environ.get(KEEP_ENV):
            timings = f"export {export.seconds:.3f} s, first image {first or 0:.3f} s, render {time.perf_counter() - started:.3f} s"
            with open(os.path.join(folder, "timings.txt"), "w") as f:
                f.write(timings + "\n")

    def _fill(self, result, frame):
        """Copies myriad's image (rows top first) into the result's passes (bottom first)."""
        width, height, channels = frame
        render_layer = result.layers[0]
        flip = lambda a: np.ascontiguousarray(a[::-1])  # noqa: E731
        rgb = [channels.get(c) for c in ("R", "G", "B")]
        if any(c is None for c in rgb):
            return
        combined = np.ones((height, width, 4), dtype=np.float32)
        for k in range(3):
            combined[..., k] = flip(rgb[k])
        _set(render_layer.passes.find_by_name("Combined", ""), combined)
        for name, _, _, _, names in PASSES:
            target = render_layer.passes.find_by_name(name, "")
            data = [channels.get(n) for n in names]
            if target is None or any(d is None for d in data):
                continue
            planes = [flip(d) for d in data]
            if name == "Denoising Normal":
                # myriad's world is Y-up: (x, y, z) there is (x, −z, y) in Blender's.
                planes = [planes[0], -planes[2], planes[1]]
            _set(target, np.stack(planes, axis=-1))


def _set(render_pass, pixels):
    if render_pass is not None:
        render_pass.rect.foreach_set(np.ascontiguousarray(pixels, dtype=np.float32).reshape(-1))


def _folder(keep, scene):
    """Where this render's scene and image go."""
    if not keep:
        return tempfile.mkdtemp(prefix="myriad-blender-")
    name = os.path.splitext(os.path.basename(bpy.data.filepath))[0] or "untitled"
    folder = os.path.join(keep, f"{name}-{scene.name}-{scene.frame_current}")
    os.makedirs(folder, exist_ok=True)
    return folder
