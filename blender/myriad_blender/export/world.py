"""The world → myriad's RON environment: a Background node's colour × strength (constant
radiance), or an Environment Texture on it (an equirectangular map × strength, its Mapping
node's Z rotation with Cycles' sign: the picture turns by −α for a Point or Vector mapping;
docs/gltf-blender.md). Anything else is named in a warning."""

import math
import os

import numpy as np

from . import ron
from .images import write_hdr
from .materials import _linked_from


def _background(world):
    tree = world.node_tree if getattr(world, "use_nodes", True) else None
    if tree is None:
        return None, None
    output = next(
        (n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld" and n.is_active_output),
        next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"), None),
    )
    if output is None:
        return tree, None
    node, _ = _linked_from(output.inputs.get("Surface"))
    return tree, node


def _rotation(node, warn, world):
    """The map's rotation about Blender's Z, in myriad's `rotate_deg`."""
    mapping, _ = _linked_from(node.inputs.get("Vector"))
    if mapping is None:
        return 0.0
    if mapping.bl_idname != "ShaderNodeMapping":
        warn(f"world '{world.name}': '{mapping.name}' on the Environment Texture's Vector is not rendered")
        return 0.0
    rot = mapping.inputs["Rotation"].default_value
    loc = mapping.inputs["Location"].default_value
    scale = mapping.inputs["Scale"].default_value
    if abs(rot[0]) > 1e-6 or abs(rot[1]) > 1e-6 or any(abs(c) > 1e-6 for c in loc) or any(abs(c - 1) > 1e-6 for c in scale):
        warn(f"world '{world.name}': only the Mapping node's Z rotation is rendered")
    alpha = math.degrees(rot[2])
    return alpha if mapping.vector_type == "TEXTURE" else -alpha


def _map_file(image, folder, warn, world):
    """A path myriad can read the map from: the image's own .exr or .hdr file, else its
    pixels written as .hdr in `folder`."""
    import bpy

    if image.packed_file is None and image.source == "FILE":
        path = bpy.path.abspath(image.filepath, library=image.library)
        if os.path.isfile(path) and os.path.splitext(path)[1].lower() in {".exr", ".hdr"}:
            return os.path.abspath(path)
    width, height = image.size
    if width == 0 or height == 0:
        warn(f"world '{world.name}': image '{image.name}' could not be read; the world renders black")
        return None
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(height, width, 4)[::-1, :, :3]
    if not image.is_float:
        # 8-bit images hold sRGB codes: decode to linear radiance, as Cycles does.
        rgb = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    path = os.path.join(folder, "world.hdr")
    write_hdr(path, rgb)
    return path


def convert(world, folder, warn):
    """The RON environment of `world` (None: black)."""
    if world is None:
        return None
    tree, node = _background(world)
    if tree is None:
        colour = tuple(world.color)
        return ron.record("Constant", radiance=ron.vec(colour)) if max(colour) > 0 else None
    if node is None:
        return None
    if node.bl_idname != "ShaderNodeBackground":
        warn(f"world '{world.name}': '{node.name}' ({node.bl_idname}) on the World Output is not rendered; black world")
        return None
    strength_socket = node.inputs["Strength"]
    if strength_socket.is_linked:
        warn(f"world '{world.name}': the Background's Strength is driven by other nodes; its own value is used")
    strength = float(strength_socket.default_value)
    source, _ = _linked_from(node.inputs["Color"])
    if source is None:
        colour = [float(c) * strength for c in node.inputs["Color"].default_value[:3]]
        return ron.record("Constant", radiance=ron.vec(colour)) if max(colour) > 0 else None
    if source.bl_idname == "ShaderNodeTexEnvironment" and source.image is not None:
        if source.projection != "EQUIRECTANGULAR":
            warn(f"world '{world.name}': a {source.projection.lower()} Environment Texture is read as equirectangular")
        path = _map_file(source.image, folder, warn, world)
        if path is None:
            return None
        return ron.record(
            "Map", path=ron.string(path), scale=ron.num(strength), rotate_deg=ron.num(_rotation(source, warn, world))
        )
    warn(f"world '{world.name}': '{source.name}' ({source.bl_idname}) on the Background's Color is not rendered; "
         "its colour value is used")
    colour = [float(c) * strength for c in node.inputs["Color"].default_value[:3]]
    return ron.record("Constant", radiance=ron.vec(colour)) if max(colour) > 0 else None
