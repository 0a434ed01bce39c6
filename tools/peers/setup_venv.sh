#!/usr/bin/env bash
# Create a Python venv with the peer renderers (Blender Cycles via the bpy wheel, Mitsuba 3).
#   PEERS_VENV=/some/where tools/peers/setup_venv.sh      (default: ~/.cache/myriad-peers)
# Needs CPython 3.11 (the bpy 5.0 wheels are cp311). About 1 GB of wheels.
set -euo pipefail
VENV="${PEERS_VENV:-$HOME/.cache/myriad-peers}"
PY="${PEERS_PYTHON:-python3.11}"
command -v "$PY" >/dev/null || PY=python3
"$PY" -c 'import sys; assert sys.version_info[:2] == (3, 11), "bpy 5.0 wheels need CPython 3.11"'
"$PY" -m venv "$VENV"
"$VENV/bin/pip" install -q --upgrade pip
"$VENV/bin/pip" install -q bpy==5.0.1 mitsuba==3.9.1 drjit==1.5.0 numpy==1.26.4 \
    OpenEXR==3.5.3 imageio==2.38.1 pillow
"$VENV/bin/python" -c 'import bpy, mitsuba; print("bpy", bpy.app.version_string, "mitsuba", mitsuba.__version__)'
# Mitsuba's llvm_ad_rgb variant needs libLLVM >= 17; Debian 12's default 15 aborts.
if ! ldconfig -p | grep -qE 'libLLVM(-1[7-9]|-[2-9][0-9]|\.so\.(1[7-9]|[2-9][0-9]))'; then
    echo "note: no libLLVM >= 17; mitsuba_render.py falls back to scalar_rgb (about 3x slower)."
    echo "      On Debian 12: apt-get update && apt-get install -y libllvm19"
fi
echo "venv ready: $VENV"
