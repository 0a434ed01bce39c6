"""The evaluated Blender scene → a myriad scene folder, written straight from the depsgraph:
`scene.ron` (camera, image size, render settings, lights and world, in Cycles' units) which
places `scene.glb` (meshes, materials and textures, written by our own glTF writer).

Why this transport: Blender's glTF exporter loses what glTF cannot say (area lights, light
radius and sun angle, the world, camera shift and depth of field) and is an operator, which
a render running off the main thread cannot call; reading the depsgraph (as Cycles,
BlendLuxCore and appleseed do) works the same in the UI, in `blender -b` and in the `bpy`
module. glTF still carries the geometry and materials, because myriad's glTF import is
already matched to Cycles on them; RON carries the rest, in myriad's own units.
"""

import os
import time
from dataclasses import dataclass, field

from . import camera, lights, ron, world
from .camera import ExportError
from .geometry import export_meshes
from .gltf import GlbWriter
from .materials import MaterialConverter

__all__ = ["Export", "ExportError", "export_scene"]


@dataclass
class Export:
    """What an export wrote and found."""

    ron: str
    size: tuple
    triangles: int = 0
    instances: int = 0
    lights: int = 0
    seconds: float = 0.0
    warnings: list = field(default_factory=list)


def export_scene(depsgraph, folder, settings):
    """Writes `folder`/scene.ron and scene.glb for the evaluated scene of `depsgraph`, with
    the render settings `settings` (the scene's `myriad` group)."""
    start = time.perf_counter()
    scene = depsgraph.scene
    warnings = []

    def warn(message):
        if message not in warnings:
            warnings.append(message)

    size = camera.resolution(scene)
    cam = scene.camera.evaluated_get(depsgraph) if scene.camera is not None else None
    camera_ron = camera.convert(scene, cam, size, warn)
    writer = GlbWriter()
    triangles, instances = export_meshes(depsgraph, writer, MaterialConverter(writer, warn), warn)
    light_list = lights.export_lights(depsgraph, warn)
    environment = world.convert(scene.world, folder, warn)
    objects = []
    if instances:
        writer.write(os.path.join(folder, "scene.glb"))
        objects.append(ron.record("Mesh", path=ron.string("scene.glb")))
    if not light_list and environment is None and not writer.has_emission():
        warn("the scene has no lights, no emissive material and a black world: it renders black")
    text = ron.scene(
        camera=camera_ron,
        film=ron.record("", resolution=f"({size[0]}, {size[1]})"),
        render=ron.record(
            "",
            spp=str(settings.samples),
            max_depth=str(settings.max_depth),
            sampler=settings.sampler,
            seed=str(settings.seed),
            clamp=_clamp(settings),
            guiding="true" if settings.guiding else None,
            caustics=None if settings.caustics else "false",
        ),
        objects=objects,
        lights=light_list,
        environment=environment,
    )
    path = os.path.join(folder, "scene.ron")
    with open(path, "w", encoding="utf-8") as f:
        f.write("// Written by myriad's Blender add-on from " + (bpy_file() or "an unsaved file") + "\n")
        f.write(text)
    return Export(
        ron=path,
        size=size,
        triangles=triangles,
        instances=instances,
        lights=len(light_list),
        seconds=time.perf_counter() - start,
        warnings=warnings,
    )


def bpy_file():
    """The .blend file's path, if saved."""
    import bpy

    return bpy.data.filepath or None


def _clamp(settings):
    """The render block's `clamp`, or None (no clamping: myriad's default)."""
    direct, indirect = float(settings.clamp_direct), float(settings.clamp_indirect)
    if direct <= 0.0 and indirect <= 0.0:
        return None
    return ron.record("", direct=f"{direct:g}", indirect=f"{indirect:g}")
