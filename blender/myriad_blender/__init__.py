"""myriad for Blender: pick "myriad" as the render engine and press F12.

The add-on reads the evaluated scene (meshes, Principled materials, lights of every kind,
the world, the camera), writes it as a myriad scene, runs `myriad render` on it and shows
the image pass after pass, with Denoising Albedo and Normal for Blender's Denoise node.
File › Export › myriad scene writes the same scene to a folder, for the command line.
Docs: docs/gltf-blender.md in myriad's repository.
"""

bl_info = {
    "name": "myriad",
    "author": "myriad's authors",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "Render Properties › Render Engine › myriad; File › Export › myriad scene",
    "description": "Render with myriad, a path tracer for scenes lit by very many lights",
    "category": "Render",
}

import bpy  # noqa: E402

from . import engine, operators, properties, ui  # noqa: E402


def register():
    bpy.utils.register_class(properties.MyriadSettings)
    bpy.types.Scene.myriad = bpy.props.PointerProperty(type=properties.MyriadSettings)
    bpy.utils.register_class(engine.MyriadRenderEngine)
    ui.register()
    operators.register()


def unregister():
    operators.unregister()
    ui.unregister()
    bpy.utils.unregister_class(engine.MyriadRenderEngine)
    del bpy.types.Scene.myriad
    bpy.utils.unregister_class(properties.MyriadSettings)
