#!/usr/bin/env python3
"""Builds the add-on as an installable Blender extension (Blender 4.2 and later):

    python3 blender/build.py [OUT_DIR]        # default: target/blender

writes OUT_DIR/myriad-VERSION.zip with blender_manifest.toml and the package at its root
(Edit › Preferences › Get Extensions › Install from Disk). The manifest is checked first.
"""

import os
import sys
import tomllib
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = os.path.join(HERE, "myriad_blender")
REQUIRED = ["schema_version", "id", "version", "name", "tagline", "maintainer", "type", "blender_version_min", "license"]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(HERE), "target", "blender")
    with open(os.path.join(PACKAGE, "blender_manifest.toml"), "rb") as f:
        manifest = tomllib.load(f)
    missing = [k for k in REQUIRED if k not in manifest]
    if missing:
        sys.exit(f"blender_manifest.toml lacks {missing}")
    if manifest["type"] != "add-on":
        sys.exit("blender_manifest.toml: type must be add-on")
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, f"{manifest['id']}-{manifest['version']}.zip")
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for root, dirs, files in os.walk(PACKAGE):
            dirs[:] = [d for d in dirs if d != "__pycache__"]
            for name in sorted(files):
                if name.endswith((".py", ".toml")):
                    full = os.path.join(root, name)
                    z.write(full, os.path.relpath(full, PACKAGE))
    print(path)


if __name__ == "__main__":
    main()
