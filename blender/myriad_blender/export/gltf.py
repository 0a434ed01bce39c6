"""A minimal glTF 2.0 binary (.glb) writer: buffers of numpy arrays, accessors, meshes,
nodes, materials and embedded images, as myriad's glTF loader reads them.

Only what the exporter needs: float32 VEC3/VEC2 vertex attributes (unindexed triangles),
one buffer, images embedded as buffer views (PNG or JPEG bytes).
"""

import json
import struct

import numpy as np

FLOAT = 5126
ARRAY_BUFFER = 34962

# What myriad's glTF loader reads a file of this generator as: Blender's conventions (solid
# glass, Blender's coat roughness default, volume absorption), which this exporter follows.
GENERATOR = "myriad Blender add-on"


class GlbWriter:
    """Collects the parts of one glTF document and writes it as a .glb."""

    def __init__(self):
        self.json = {
            "asset": {"version": "2.0", "generator": GENERATOR},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
            "images": [],
            "textures": [],
            "samplers": [],
            "extensionsUsed": [],
        }
        self.chunks = []
        self.length = 0

    def _view(self, data, target=None):
        """Appends `data` (bytes) as a buffer view (4-byte aligned); its index."""
        pad = (-self.length) % 4
        if pad:
            self.chunks.append(b"\0" * pad)
            self.length += pad
        view = {"buffer": 0, "byteOffset": self.length, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.chunks.append(data)
        self.length += len(data)
        self.json["bufferViews"].append(view)
        return len(self.json["bufferViews"]) - 1

    def accessor(self, array):
        """A float accessor over an (n, k) float32 array (k = 2 or 3); its index."""
        array = np.ascontiguousarray(array, dtype=np.float32)
        n, k = array.shape
        view = self._view(array.tobytes(), ARRAY_BUFFER)
        acc = {"bufferView": view, "componentType": FLOAT, "count": int(n), "type": {2: "VEC2", 3: "VEC3"}[k]}
        if k == 3 and n:
            acc["min"] = [float(x) for x in array.min(axis=0)]
            acc["max"] = [float(x) for x in array.max(axis=0)]
        self.json["accessors"].append(acc)
        return len(self.json["accessors"]) - 1

    def image(self, data, mime):
        """An embedded image (PNG or JPEG bytes) and a texture of it; the texture's index."""
        view = self._view(data)
        self.json["images"].append({"bufferView": view, "mimeType": mime})
        self.json["textures"].append({"source": len(self.json["images"]) - 1})
        return len(self.json["textures"]) - 1

    def material(self, material):
        """Adds a glTF material (a dict); its index."""
        for ext in material.get("extensions", {}):
            if ext not in self.json["extensionsUsed"]:
                self.json["extensionsUsed"].append(ext)
        self.json["materials"].append(material)
        return len(self.json["materials"]) - 1

    def has_emission(self):
        """Whether some material emits."""
        return any("emissiveFactor" in m for m in self.json["materials"])

    def mesh(self, name, primitives):
        """A mesh of `primitives` (dicts of attribute accessors and a material); its index."""
        self.json["meshes"].append({"name": name, "primitives": primitives})
        return len(self.json["meshes"]) - 1

    def node(self, name, mesh, matrix):
        """A node placing `mesh` by `matrix` (16 floats, column-major) in the scene."""
        node = {"name": name, "mesh": mesh}
        if matrix is not None:
            node["matrix"] = [float(x) for x in matrix]
        self.json["nodes"].append(node)
        self.json["scenes"][0]["nodes"].append(len(self.json["nodes"]) - 1)

    def write(self, path):
        """Writes the .glb to `path`."""
        doc = {k: v for k, v in self.json.items() if v != []}
        body = b"".join(self.chunks)
        body += b"\0" * ((-len(body)) % 4)
        if body:
            doc["buffers"] = [{"byteLength": len(body)}]
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * ((-len(text)) % 4)
        total = 12 + 8 + len(text) + (8 + len(body) if body else 0)
        with open(path, "wb") as f:
            f.write(struct.pack("<4sII", b"glTF", 2, total))
            f.write(struct.pack("<I4s", len(text), b"JSON"))
            f.write(text)
            if body:
                f.write(struct.pack("<I4s", len(body), b"BIN\0"))
                f.write(body)
