"""The scene's camera and image size → myriad's RON camera and film, as Cycles frames them
(docs/gltf-blender.md): the output size is the resolution × percentage; the field of view is
the sensor's over the focal length along the fitted dimension (Auto: the sensor width on the
larger image side); the shift is in units of that dimension; depth of field is a thin lens of
radius focal length / (2 · f-stop) focused at the focus distance (or the focus object's
distance along the view axis)."""

import math

import numpy as np

from . import ron
from .geometry import y_up_points


class ExportError(Exception):
    """A scene myriad cannot render as it is, with what to change."""


def resolution(scene):
    """The output size Blender renders: resolution × percentage / 100, rounded down."""
    r = scene.render
    pct = r.resolution_percentage
    return max(1, r.resolution_x * pct // 100), max(1, r.resolution_y * pct // 100)


def _y_up(v):
    return tuple(y_up_points(np.array([v], dtype=np.float64))[0])


def convert(scene, camera, size, warn):
    """The RON camera for the camera object `camera` rendering an image of `size`."""
    if camera is None:
        raise ExportError("the scene has no active camera: add a camera and make it active (Scene Properties › Camera)")
    cam = camera.data
    if cam.type != "PERSP":
        raise ExportError(f"camera '{camera.name}' is {cam.type.lower()}; myriad renders perspective cameras only")
    r = scene.render
    if abs(r.pixel_aspect_x - r.pixel_aspect_y) > 1e-6:
        warn("the render's pixel aspect is not 1:1; myriad renders square pixels")
    if r.use_border:
        warn("Render Region is on; myriad renders the whole frame")
    fit = cam.sensor_fit
    if fit == "VERTICAL":
        sensor, fit_name = cam.sensor_height, "Vertical"
    else:
        sensor, fit_name = cam.sensor_width, "Horizontal" if fit == "HORIZONTAL" else "Auto"
    fov = 2.0 * math.atan(0.5 * sensor / cam.lens)
    m = np.array(camera.matrix_world, dtype=np.float64)
    eye, y, z = m[:3, 3], m[:3, 1], m[:3, 2]
    forward = -z / np.linalg.norm(z)
    up = y / np.linalg.norm(y)
    lens = None
    dof = cam.dof
    if dof.use_dof and dof.aperture_fstop > 0.0:
        if dof.focus_object is not None:
            target = np.array(dof.focus_object.matrix_world, dtype=np.float64)[:3, 3]
            focus = abs(float(np.dot(forward, eye - target)))
        else:
            focus = float(dof.focus_distance)
        if dof.aperture_blades >= 3 or abs(dof.aperture_ratio - 1.0) > 1e-6:
            warn(f"camera '{camera.name}': aperture blades and ratio are not rendered; the aperture is a disk")
        radius = cam.lens * 1e-3 / (2.0 * dof.aperture_fstop)
        if focus > 0.0:
            lens = ron.record("", aperture_radius=ron.num(radius), focus_distance=ron.num(focus))
        else:
            warn(f"camera '{camera.name}': a focus distance of 0 keeps everything sharp")
    return ron.record(
        "Perspective",
        eye=ron.vec(_y_up(eye)),
        look_at=ron.vec(_y_up(eye + forward)),
        up=ron.vec(_y_up(up)),
        fov_deg=ron.num(math.degrees(fov)),
        fit=fit_name,
        shift=ron.vec((cam.shift_x, cam.shift_y)),
        depth_of_field=lens,
    )
