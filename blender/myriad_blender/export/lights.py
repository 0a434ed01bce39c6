"""Blender lights → myriad's RON lights, in Cycles' units (Cycles 5.0 source, each checked
against a Cycles render; docs/gltf-blender.md).

With P = colour × (temperature colour) × power × 2^exposure:
- point and spot: intensity P/(4π) W/sr; with a radius r a lamp of radiance P/(4π²r²), a
  disk facing each receiver with Soft Falloff on (Blender's default), else a sphere; a spot's
  cone fades by Cycles' smoothstep over the blend, on each light ray's own direction;
- sun: irradiance P W/m²; with an angle, a disk of that angular diameter;
- area (rectangle, square, disk, ellipse): radiance P/(π·A) from its local −Z face, A its
  area with the object's scale, spread as Cycles has it.
Lamps cast no shadow and are seen by the camera only where the object's Ray Visibility ›
Camera is on (off by default), as in Cycles. With Normalize off, Cycles takes P/π as the
radiance instead (and P/π as a point's intensity).
"""

import math

import numpy as np

from . import ron
from .geometry import y_up_points


def _column(matrix, k):
    return np.array([matrix[0][k], matrix[1][k], matrix[2][k]], dtype=np.float64)


def _y_up(v):
    return tuple(y_up_points(np.array([v], dtype=np.float64))[0])


def _power(light, warn, name):
    """P per channel: colour × temperature colour × power × 2^exposure, × a constant
    Emission node's colour × strength."""
    colour = np.array(light.color[:3], dtype=np.float64)
    if getattr(light, "use_temperature", False):
        colour = colour * np.array(light.temperature_color[:3])
    factor = light.energy * 2.0 ** getattr(light, "exposure", 0.0)
    tree = light.node_tree if getattr(light, "use_nodes", False) else None
    if tree is not None:
        emission = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeEmission"), None)
        if emission is not None:
            c, s = emission.inputs["Color"], emission.inputs["Strength"]
            if c.is_linked or s.is_linked:
                warn(f"light '{name}': its Emission node is driven by other nodes, which myriad does not evaluate")
            else:
                colour = colour * np.array(c.default_value[:3])
                factor *= s.default_value
    return colour * factor


def _flags(obj, light, warn):
    cycles = getattr(light, "cycles", None)
    if not getattr(light, "use_shadow", True):
        warn(f"light '{obj.name}': Cast Shadow is off, which myriad does not render; it casts shadows")
    if cycles is not None and not getattr(cycles, "use_multiple_importance_sampling", True):
        warn(f"light '{obj.name}': Multiple Importance is off; myriad's rays still see the lamp")
    link = getattr(obj, "light_linking", None)
    if link is not None and (getattr(link, "receiver_collection", None) or getattr(link, "blocker_collection", None)):
        warn(f"light '{obj.name}': light and shadow linking are not rendered; it lights everything")


def convert(obj, matrix, warn):
    """The RON light of a Blender light object placed by `matrix`; None (with a warning)
    where myriad has nothing for it."""
    light = obj.data
    name = obj.name
    if getattr(getattr(light, "cycles", None), "is_portal", False):
        warn(f"light '{name}': portals guide Cycles' world sampling and emit nothing; left out")
        return None
    _flags(obj, light, warn)
    p = _power(light, warn, name)
    normalize = getattr(light, "normalize", True)
    visible = "true" if getattr(obj, "visible_camera", False) else "false"
    position = _y_up(_column(matrix, 3))
    z = _column(matrix, 2)
    kind = light.type
    if kind in {"POINT", "SPOT"}:
        r = float(light.shadow_soft_size)
        if normalize:
            intensity = p / (4.0 * math.pi)
        else:
            # Cycles' radiance is P/π then: a lamp's intensity π r² L, a point's P/π.
            intensity = p * r * r if r > 0.0 else p / math.pi
        common = {
            "position": ron.vec(position),
            "intensity": ron.vec(intensity),
        }
        lamp = {}
        if r > 0.0:
            lamp = {
                "radius": ron.num(r),
                "soft_falloff": "true" if getattr(light, "use_soft_falloff", True) else "false",
                "visible": visible,
            }
        if kind == "POINT":
            return ron.record("Point", **common, **lamp)
        scale = np.array(matrix, dtype=np.float64)[:3, :3]
        lengths = np.linalg.norm(scale, axis=0)
        if abs(lengths[0] - lengths[2]) > 1e-4 * lengths[2] or abs(lengths[1] - lengths[2]) > 1e-4 * lengths[2]:
            warn(f"light '{name}': a non-uniform scale squashes a spot's cone in Cycles; myriad's stays round")
        half = 0.5 * float(light.spot_size)
        cos_outer = math.cos(half)
        cos_inner = min(1.0, cos_outer + (1.0 - cos_outer) * float(light.spot_blend))
        return ron.record(
            "Spot",
            **common,
            direction=ron.vec(_y_up(-z / np.linalg.norm(z))),
            inner_deg=ron.num(math.degrees(math.acos(cos_inner))),
            outer_deg=ron.num(math.degrees(half)),
            falloff="Smoothstep",
            **lamp,
        )
    if kind == "SUN":
        angle = float(light.angle)
        irradiance = p
        if not normalize and angle > 0.0:
            irradiance = p * math.pi * math.sin(0.5 * angle) ** 2
        return ron.record(
            "Directional",
            direction=ron.vec(_y_up(-z / np.linalg.norm(z))),
            irradiance=ron.vec(irradiance),
            angle_deg=ron.num(math.degrees(angle)),
            visible=visible,
        )
    if kind == "AREA":
        shape = light.shape
        sx = float(light.size)
        sy = float(light.size_y) if shape in {"RECTANGLE", "ELLIPSE"} else sx
        x, y = _column(matrix, 0) * sx, _column(matrix, 1) * sy
        ellipse = shape in {"DISK", "ELLIPSE"}
        area = np.linalg.norm(x) * np.linalg.norm(y) * (math.pi / 4.0 if ellipse else 1.0)
        if area <= 0.0:
            warn(f"light '{name}': an area light of zero size emits nothing; left out")
            return None
        radiance = p / (math.pi * area) if normalize else p / math.pi
        # Emitting towards local −Z: u × v = x × (−y) = −(x × y).
        return ron.record(
            "Area",
            center=ron.vec(position),
            u=ron.vec(_y_up(x)),
            v=ron.vec(_y_up(-y)),
            shape="Ellipse" if ellipse else "Rectangle",
            radiance=ron.vec(radiance),
            spread_deg=ron.num(math.degrees(float(getattr(light, "spread", math.pi)))),
            visible=visible,
        )
    warn(f"light '{name}': a {kind} light is not rendered by myriad")
    return None


def export_lights(depsgraph, warn):
    """Every light instance of `depsgraph` as RON."""
    out = []
    for inst in depsgraph.object_instances:
        if inst.object.type == "LIGHT":
            light = convert(inst.object, inst.matrix_world, warn)
            if light is not None:
                out.append(light)
    return out
