"""Image files from pixels, with nothing but numpy and the standard library: 8-bit PNG for
textures, Radiance RGBE (.hdr) for environment maps (what myriad reads besides EXR)."""

import struct
import zlib

import numpy as np


def png_bytes(rgba8):
    """An 8-bit RGBA PNG of an (h, w, 4) uint8 array, top row first."""
    h, w, _ = rgba8.shape
    raw = b"".join(b"\0" + rgba8[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")


def linear_to_srgb8(rgb):
    """Linear values to 8-bit sRGB codes (the sRGB transfer curve)."""
    c = np.clip(rgb, 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def write_hdr(path, rgb):
    """A Radiance RGBE file of an (h, w, 3) float array (linear, top row first)."""
    rgb = np.maximum(np.nan_to_num(rgb.astype(np.float32), nan=0.0, posinf=0.0), 0.0)
    h, w, _ = rgb.shape
    peak = rgb.max(axis=2)
    mantissa, exponent = np.frexp(peak)
    scale = np.where(peak > 1e-32, mantissa * 256.0 / np.maximum(peak, 1e-32), 0.0)
    rgbe = np.zeros((h, w, 4), dtype=np.uint8)
    rgbe[..., :3] = np.clip(rgb * scale[..., None], 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(peak > 1e-32, exponent + 128, 0).astype(np.uint8)
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {h} +X {w}\n".encode())
        if not 8 <= w <= 0x7FFF:
            f.write(rgbe.tobytes())
            return
        # Run-length scanlines of literal runs only: a flat scanline whose first pixel reads
        # (2, 2, ...) would be taken for a run-length one by a reader.
        for y in range(h):
            f.write(bytes([2, 2, w >> 8, w & 0xFF]))
            for c in range(4):
                channel = rgbe[y, :, c].tobytes()
                for start in range(0, w, 128):
                    piece = channel[start:start + 128]
                    f.write(bytes([len(piece)]) + piece)
