"""Blender materials → glTF materials, as myriad renders them (Cycles' Principled BSDF).

myriad's glTF import is matched to Cycles on what Blender's own glTF exporter writes, so a
material here follows the exporter's mapping (docs/gltf-blender.md), with three differences
where the exporter loses what Cycles renders: IOR is always written, coat roughness always,
and every emitter emits from both faces (Cycles does; the exporter writes `doubleSided` from
backface culling). What the mapping cannot express is named in a warning (the material and
the node), never changed silently.

Handled: a Principled BSDF, Diffuse, Glossy (metal), Glass, Emission or Transparent BSDF on
the active Material Output's Surface, with constant inputs or an Image Texture on Base
Color, Emission Color and Alpha, and a Normal Map node with an Image Texture on Normal; a
Volume Absorption on the Volume of a glass.
"""

import os

import numpy as np

from .images import linear_to_srgb8, png_bytes

# Principled inputs whose effect myriad does not render yet: (socket, default, what).
UNRENDERED_INPUTS = [
    ("Subsurface Weight", 0.0, "subsurface scattering"),
    ("Diffuse Roughness", 0.0, "diffuse roughness"),
    ("Thin Film Thickness", 0.0, "thin film"),
]

# Nodes that only pass a value on.
PASS_THROUGH = {"NodeReroute"}


def _linked_from(socket):
    """The node (and its output socket) feeding `socket`, through reroutes; None."""
    while socket is not None and socket.is_linked:
        link = socket.links[0]
        if not link.is_valid or link.is_muted:
            return None, None
        node = link.from_node
        if node.bl_idname in PASS_THROUGH:
            socket = node.inputs[0] if node.inputs else None
            continue
        return node, link.from_socket
    return None, None


def _active_output(tree):
    """The Material Output node Cycles renders with."""
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    for n in outputs:
        if n.is_active_output and n.target in {"ALL", "CYCLES"}:
            return n
    return next((n for n in outputs if n.target in {"ALL", "CYCLES"}), None)


def _first_principled(tree):
    """The first Principled BSDF of `tree` (node order), as Blender's glTF exporter takes."""
    return next((n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled" and not n.mute), None)


class MaterialConverter:
    """Turns the scene's materials into glTF materials of one [`GlbWriter`], each once."""

    def __init__(self, writer, warn):
        self.writer = writer
        self.warn = warn
        self.indices = {}
        self.textures = {}
        self.default = None

    def index(self, material):
        """The glTF material of a Blender material (None: Cycles' default grey surface)."""
        if material is None:
            if self.default is None:
                self.default = self.writer.material(_base("<default>", (0.8, 0.8, 0.8, 1.0), 0.0, 0.5))
            return self.default
        key = material.name_full
        if key not in self.indices:
            self.indices[key] = self.writer.material(self.convert(material))
        return self.indices[key]

    # Reading sockets --------------------------------------------------------------------

    def _where(self, material, node=None, socket=None):
        where = f"material '{material.name}'"
        if node is not None:
            where += f", node '{node.name}'"
        if socket is not None:
            where += f", input '{socket}'"
        return where

    def value(self, material, node, name, default):
        """The constant on input `name` of `node` (its own value, or an RGB or Value node's);
        anything else linked there is warned about and its default value used."""
        socket = node.inputs.get(name)
        if socket is None:
            return default
        source, out = _linked_from(socket)
        if source is None:
            return _plain(socket.default_value)
        if source.bl_idname == "ShaderNodeRGB":
            return _plain(out.default_value)
        if source.bl_idname == "ShaderNodeValue":
            return _plain(out.default_value)
        self.warn(
            f"{self._where(material, node, name)}: '{source.name}' ({source.bl_idname}) drives it, which myriad does "
            f"not evaluate; it renders with the input's own value {_fmt(socket.default_value)}"
        )
        return _plain(socket.default_value)

    def image_texture(self, material, node, name, role):
        """A texture for input `name` when an Image Texture feeds it (its colour, or its
        alpha for `role == 'alpha'`); None when it is unlinked or held a constant."""
        socket = node.inputs.get(name)
        if socket is None:
            return None
        source, out = _linked_from(socket)
        if source is None or source.bl_idname != "ShaderNodeTexImage":
            return None
        if role == "alpha" and out.name != "Alpha":
            return None
        if source.image is None:
            self.warn(f"{self._where(material, source)}: the Image Texture has no image; its input renders black")
            return None
        vector, _ = _linked_from(source.inputs.get("Vector"))
        if vector is not None and vector.bl_idname != "ShaderNodeUVMap":
            self.warn(
                f"{self._where(material, vector)}: texture coordinates from '{vector.bl_idname}' are not exported; "
                "the mesh's active render UV map is used"
            )
        return self.texture(material, source.image, role)

    def texture(self, material, image, role):
        """The glTF texture of `image` (embedded), or None with a warning."""
        key = (image.name_full, role)
        if key in self.textures:
            return self.textures[key]
        colour_data = role in {"color", "alpha"}
        space = image.colorspace_settings.name
        if colour_data and space not in {"sRGB", "Linear Rec.709", "Linear"} or (not colour_data and space == "sRGB"):
            self.warn(
                f"{self._where(material)}: image '{image.name}' is marked {space}; it is read as "
                f"{'sRGB' if colour_data else 'non-colour'} data"
            )
        data = _image_bytes(image, colour_data)
        if data is None:
            self.warn(f"{self._where(material)}: image '{image.name}' could not be read; the input's value is used")
            self.textures[key] = None
            return None
        self.textures[key] = self.writer.image(*data)
        return self.textures[key]

    # Materials ----------------------------------------------------------------------------

    def convert(self, material):
        """The glTF material for `material`."""
        tree = material.node_tree if getattr(material, "use_nodes", True) else None
        if tree is None:
            colour = tuple(material.diffuse_color)
            return _base(material.name, colour, material.metallic, material.roughness)
        output = _active_output(tree)
        if output is None:
            self.warn(f"{self._where(material)}: no Material Output node; it renders black")
            return _base(material.name, (0.0, 0.0, 0.0, 1.0), 0.0, 1.0)
        node, _ = _linked_from(output.inputs.get("Surface"))
        if node is None:
            return _base(material.name, (0.0, 0.0, 0.0, 1.0), 0.0, 1.0)
        kind = node.bl_idname
        if kind == "ShaderNodeBsdfPrincipled":
            gltf = self.principled(material, node)
        elif kind == "ShaderNodeEmission":
            gltf = self.emission(material, node)
        elif kind == "ShaderNodeBsdfDiffuse":
            colour = self.value(material, node, "Color", (0.8, 0.8, 0.8, 1.0))
            gltf = _base(material.name, colour, 0.0, 1.0)
            gltf["extensions"] = {"KHR_materials_specular": {"specularFactor": 0.0}}
            self._base_texture(material, node, "Color", gltf)
        elif kind in {"ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic", "ShaderNodeBsdfMetallic"}:
            colour = self.value(material, node, "Color", (0.8, 0.8, 0.8, 1.0))
            if kind == "ShaderNodeBsdfMetallic":
                colour = self.value(material, node, "Base Color", colour)
            roughness = self.value(material, node, "Roughness", 0.5)
            gltf = _base(material.name, colour, 1.0, roughness)
        elif kind == "ShaderNodeBsdfGlass":
            colour = self.value(material, node, "Color", (1.0, 1.0, 1.0, 1.0))
            gltf = _base(material.name, colour, 0.0, self.value(material, node, "Roughness", 0.0))
            ior = float(self.value(material, node, "IOR", 1.5))
            gltf["extensions"] = {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": ior}}
        elif kind == "ShaderNodeBsdfTransparent":
            gltf = _base(material.name, (1.0, 1.0, 1.0, 0.0), 0.0, 1.0)
            gltf["alphaMode"] = "BLEND"
        else:
            principled = _first_principled(tree)
            what = f"'{node.name}' ({kind}) on the Surface is not rendered as Cycles renders it"
            if principled is not None:
                self.warn(f"{self._where(material)}: {what}; myriad uses the Principled BSDF '{principled.name}' in it")
                gltf = self.principled(material, principled)
            else:
                self.warn(f"{self._where(material)}: {what}; it renders grey")
                gltf = _base(material.name, (0.8, 0.8, 0.8, 1.0), 0.0, 0.5)
        self.volume(material, output, gltf)
        return gltf

    def _base_texture(self, material, node, name, gltf):
        tex = self.image_texture(material, node, name, "color")
        if tex is not None:
            gltf["pbrMetallicRoughness"]["baseColorTexture"] = {"index": tex}
            gltf["pbrMetallicRoughness"]["baseColorFactor"][:3] = [1.0, 1.0, 1.0]

    def principled(self, material, node):
        """A Principled BSDF, as Blender's glTF exporter maps it (module docs)."""
        v = lambda name, default: self.value(material, node, name, default)  # noqa: E731
        colour = v("Base Color", (0.8, 0.8, 0.8, 1.0))
        alpha = float(v("Alpha", 1.0))
        gltf = _base(material.name, colour[:3] + (alpha,), v("Metallic", 0.0), v("Roughness", 0.5))
        self._base_texture(material, node, "Base Color", gltf)
        for name in ("Metallic", "Roughness"):
            if self.image_texture(material, node, name, "data") is not None:
                self.warn(f"{self._where(material, node, name)}: a texture there is not rendered; its value is used")
        alpha_texture = self.image_texture(material, node, "Alpha", "alpha")
        if alpha < 1.0 or alpha_texture is not None:
            gltf["alphaMode"] = "BLEND"
        ext = {}
        # Specular IOR Level and Tint: s = 2·level; below 1 a factor, above 1 on the colour.
        s = 2.0 * float(v("Specular IOR Level", 0.5))
        tint = tuple(float(c) for c in v("Specular Tint", (1.0, 1.0, 1.0, 1.0))[:3])
        specular = {}
        if s < 1.0:
            specular["specularFactor"] = s
        colour_factor = tuple(c * max(s, 1.0) for c in tint)
        if any(abs(c - 1.0) > 1e-6 for c in colour_factor):
            specular["specularColorFactor"] = list(colour_factor)
        if specular:
            ext["KHR_materials_specular"] = specular
        ior = float(v("IOR", 1.5))
        if abs(ior - 1.5) > 1e-6:
            ext["KHR_materials_ior"] = {"ior": ior}
        transmission = float(v("Transmission Weight", 0.0))
        if transmission > 0.0:
            ext["KHR_materials_transmission"] = {"transmissionFactor": transmission}
        coat = float(v("Coat Weight", 0.0))
        if coat > 0.0:
            ext["KHR_materials_clearcoat"] = {
                "clearcoatFactor": coat,
                "clearcoatRoughnessFactor": float(v("Coat Roughness", 0.03)),
            }
            if abs(float(v("Coat IOR", 1.5)) - 1.5) > 1e-6:
                self.warn(f"{self._where(material, node, 'Coat IOR')}: myriad's coat has IOR 1.5")
            if any(abs(c - 1.0) > 1e-6 for c in v("Coat Tint", (1.0, 1.0, 1.0, 1.0))[:3]):
                self.warn(f"{self._where(material, node, 'Coat Tint')}: a tinted coat renders untinted")
        self._sheen(material, node, ext)
        self._anisotropy(material, node, ext)
        for name, default, what in UNRENDERED_INPUTS:
            value = v(name, default)
            if isinstance(value, float) and value > default + 1e-6:
                self.warn(f"{self._where(material, node, name)}: {what} is not rendered by myriad")
        self._emission(material, node, "Emission Color", "Emission Strength", gltf, ext)
        self._normal_map(material, node, gltf)
        if ext:
            gltf["extensions"] = ext
        return gltf

    def _sheen(self, material, node, ext):
        """Sheen Weight × Sheen Tint and Sheen Roughness, as KHR_materials_sheen."""
        v = lambda name, default: self.value(material, node, name, default)  # noqa: E731
        weight = float(v("Sheen Weight", 0.0))
        if weight <= 0.0:
            return
        tint = [float(c) for c in v("Sheen Tint", (1.0, 1.0, 1.0, 1.0))[:3]]
        ext["KHR_materials_sheen"] = {
            "sheenColorFactor": [weight * c for c in tint],
            "sheenRoughnessFactor": float(v("Sheen Roughness", 0.5)),
        }

    def _anisotropy(self, material, node, ext):
        """Anisotropic and its rotation, as KHR_materials_anisotropy: myriad stretches along
        Blender's default tangent (radial about the object's Z), which a linked Tangent
        replaces."""
        v = lambda name, default: self.value(material, node, name, default)  # noqa: E731
        strength = float(v("Anisotropic", 0.0))
        if strength <= 0.0:
            return
        rotation = float(v("Anisotropic Rotation", 0.0)) * 2.0 * np.pi
        ext["KHR_materials_anisotropy"] = {"anisotropyStrength": strength, "anisotropyRotation": rotation}
        if node.inputs.get("Tangent") is not None and node.inputs["Tangent"].is_linked:
            self.warn(f"{self._where(material, node, 'Tangent')}: myriad stretches along the default (radial) tangent")

    def emission(self, material, node):
        """An Emission shader: a black surface that emits colour × strength."""
        gltf = _base(material.name, (0.0, 0.0, 0.0, 1.0), 0.0, 1.0)
        ext = {"KHR_materials_specular": {"specularFactor": 0.0}}
        self._emission(material, node, "Color", "Strength", gltf, ext)
        gltf["extensions"] = ext
        return gltf

    def _emission(self, material, node, colour_name, strength_name, gltf, ext):
        colour = [float(c) for c in self.value(material, node, colour_name, (1.0, 1.0, 1.0, 1.0))[:3]]
        strength = float(self.value(material, node, strength_name, 0.0))
        texture = self.image_texture(material, node, colour_name, "color")
        if texture is not None:
            colour = [1.0, 1.0, 1.0]
            gltf["emissiveTexture"] = {"index": texture}
        radiance = [c * strength for c in colour]
        peak = max(radiance)
        if peak <= 0.0:
            return
        if peak > 1.0:
            gltf["emissiveFactor"] = [c / peak for c in radiance]
            ext["KHR_materials_emissive_strength"] = {"emissiveStrength": peak}
        else:
            gltf["emissiveFactor"] = radiance

    def _normal_map(self, material, node, gltf):
        socket = node.inputs.get("Normal")
        source, _ = _linked_from(socket)
        if source is None:
            return
        if source.bl_idname != "ShaderNodeNormalMap" or source.space != "TANGENT":
            self.warn(f"{self._where(material, source)}: only a tangent-space Normal Map node is rendered on Normal")
            return
        texture = self.image_texture(material, source, "Color", "data")
        if texture is None:
            return
        normal = {"index": texture}
        strength = float(self.value(material, source, "Strength", 1.0))
        if abs(strength - 1.0) > 1e-6:
            normal["scale"] = strength
        gltf["normalTexture"] = normal

    def volume(self, material, output, gltf):
        """A Volume Absorption on a glass's Volume: Beer–Lambert inside it."""
        node, _ = _linked_from(output.inputs.get("Volume"))
        if node is None:
            return
        transmits = "KHR_materials_transmission" in gltf.get("extensions", {})
        if node.bl_idname != "ShaderNodeVolumeAbsorption" or not transmits:
            self.warn(f"{self._where(material, node)}: this volume is not rendered (myriad absorbs inside glass only)")
            return
        colour = [float(c) for c in self.value(material, node, "Color", (0.8, 0.8, 0.8, 1.0))[:3]]
        density = float(self.value(material, node, "Density", 1.0))
        if density <= 0.0:
            return
        gltf["extensions"]["KHR_materials_volume"] = {
            "thicknessFactor": 1.0,
            "attenuationColor": colour,
            "attenuationDistance": 1.0 / density,
        }


def _plain(value):
    """A socket value as a float or a tuple."""
    try:
        return tuple(float(x) for x in value)
    except TypeError:
        return float(value)


def _fmt(value):
    value = _plain(value)
    if isinstance(value, tuple):
        return "(" + ", ".join(f"{x:.3g}" for x in value) + ")"
    return f"{value:.3g}"


def _base(name, colour, metallic, roughness):
    """A glTF metallic-roughness material; every face emits and reflects on both sides, as
    Cycles renders meshes."""
    colour = list(colour) + [1.0] * (4 - len(colour))
    return {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [min(max(float(c), 0.0), 1.0) for c in colour[:4]],
            "metallicFactor": float(metallic),
            "roughnessFactor": float(roughness),
        },
        "doubleSided": True,
    }


def _image_bytes(image, colour_data):
    """An image's PNG or JPEG bytes and MIME type: the file as it is where it is one (packed
    or on disk), else its pixels as an 8-bit PNG; None when it cannot be read."""
    raw = None
    if image.packed_file is not None:
        raw = bytes(image.packed_file.data)
    elif image.source == "FILE":
        import bpy

        path = bpy.path.abspath(image.filepath, library=image.library)
        if os.path.isfile(path):
            with open(path, "rb") as f:
                raw = f.read()
    if raw is not None:
        if raw.startswith(b"\x89PNG\r\n\x1a\n"):
            return raw, "image/png"
        if raw.startswith(b"\xff\xd8"):
            return raw, "image/jpeg"
    # Any other file (EXR, TIFF, ...) or a generated image: its pixels.
    width, height = image.size
    if width == 0 or height == 0:
        return None
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgba = pixels.reshape(height, width, 4)[::-1]
    if image.is_float and colour_data:
        out = np.empty((height, width, 4), dtype=np.uint8)
        out[..., :3] = linear_to_srgb8(rgba[..., :3])
        out[..., 3] = np.round(np.clip(rgba[..., 3], 0, 1) * 255).astype(np.uint8)
    else:
        out = np.round(np.clip(rgba, 0, 1) * 255).astype(np.uint8)
    return png_bytes(out), "image/png"
