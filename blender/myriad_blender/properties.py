"""The render settings a scene keeps for myriad: `scene.myriad`."""

import bpy

# The light samplers of `myriad render --sampler`, in its order, and its default.
SAMPLERS = [
    ("cells", "cells", "Per-region light tables (8 to 1024 lights), the tree elsewhere: the default"),
    ("tree", "tree", "A light tree: per-point weighting at any light count"),
    ("learned", "learned", "The tree, learning which lights are blocked: interiors lit from other rooms"),
    ("power", "power", "By emitted power"),
    ("uniform", "uniform", "Every light alike"),
    ("local", "local", "Every light weighed at every point: O(n), small scenes only"),
    ("all", "all", "Every light, one shadow ray each: O(n), small scenes only"),
]


class MyriadSettings(bpy.types.PropertyGroup):
    """myriad's settings of one scene."""

    samples: bpy.props.IntProperty(
        name="Samples", description="Samples per pixel", default=64, min=1, soft_max=4096, max=1 << 20
    )
    time: bpy.props.FloatProperty(
        name="Time Limit",
        description="Render for this many seconds (whole passes) instead of a number of samples; 0: use Samples",
        default=0.0,
        min=0.0,
        soft_max=3600.0,
        unit="TIME_ABSOLUTE",
    )
    sampler: bpy.props.EnumProperty(
        name="Light Sampler", description="How each shading point chooses a light", items=SAMPLERS, default="cells"
    )
    max_depth: bpy.props.IntProperty(
        name="Max Depth",
        description="Most scattering events on a path (Cycles' Max Bounces + 1; 1 is direct light only)",
        default=9,
        min=1,
        max=1024,
    )
    clamp_direct: bpy.props.FloatProperty(
        name="Clamp Direct",
        description="Scale down a direct-light sample whose channels sum above this (Cycles' Clamp Direct); "
        "0: no clamping. Clamping darkens fireflies and biases the image",
        default=0.0,
        min=0.0,
    )
    clamp_indirect: bpy.props.FloatProperty(
        name="Clamp Indirect",
        description="The same for indirect light (Cycles' Clamp Indirect); 0: no clamping",
        default=0.0,
        min=0.0,
    )
    guiding: bpy.props.BoolProperty(
        name="Path Guiding",
        description="Paths learn where light comes from and go there more often (light through glass, "
        "glossy bounces); unbiased, but at equal time it does not pay on most scenes yet",
        default=False,
    )
    caustics: bpy.props.BoolProperty(
        name="Caustics",
        description="Light that reaches a surface only through smooth glass (a lamp in a glass globe, the sun "
        "through a glass ball) is solved for, where Cycles needs Shadow Caustics flags, and the highlights "
        "glossy surfaces throw from point and spot lights are traced from the lights; off: left to chance, "
        "and a point light's or the sun's through glass never found",
        default=True,
    )
    seed: bpy.props.IntProperty(
        name="Seed", description="Seed of every random number: the same seed gives the same image", default=0, min=0
    )
    binary: bpy.props.StringProperty(
        name="Executable",
        description="The myriad program; empty: MYRIAD_BIN, else `myriad` on the PATH",
        default="",
        subtype="FILE_PATH",
    )
