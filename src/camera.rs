//! The pinhole perspective camera: (pixel, jitter) → primary ray.
//!
//! Owns: the camera model shared by every loader (RON look-at, glTF node matrix). The image
//! plane follows glTF: the camera looks down its local −Z with +Y up, `yfov` is the vertical
//! field of view, and the horizontal extent follows the output aspect ratio (so `yfov` is kept
//! when the ratio changes; docs/conventions.md). Pixel (0,0) is the top-left corner; the
//! pixel filter is a 1-pixel box, as in the Cycles references.

use crate::geometry::Ray;
use crate::math::{Mat4, UVec2, Vec2, Vec3A};
use glam::Quat;

/// A camera position must be finite.
fn check_position(name: &str, p: Vec3A) -> Result<(), String> {
    if p.is_finite() { Ok(()) } else { Err(format!("its {name} {p} is not finite")) }
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    origin: Vec3A,
    right: Vec3A,
    up: Vec3A,
    forward: Vec3A,
    tan_half_fov_y: f32,
}

impl Camera {
    /// A camera at `eye` looking at `target`, `up` giving the vertical, vertical field of view
    /// `yfov` in radians. An error says what makes the view degenerate, with the values.
    pub fn look_at(eye: Vec3A, target: Vec3A, up: Vec3A, yfov: f32) -> Result<Self, String> {
        check_position("eye", eye)?;
        check_position("target", target)?;
        let d = target - eye;
        if !d.is_finite() {
            return Err(format!("the eye {eye} and the target {target} are too far apart"));
        }
        // Scaled first, so that a long but finite view does not overflow its length.
        let forward = (d / d.abs().max_element())
            .try_normalize()
            .ok_or_else(|| format!("the eye {eye} is at the target {target}"))?;
        let right = forward
            .cross(up)
            .try_normalize()
            .ok_or_else(|| format!("up {up} is zero or parallel to the view direction {forward}"))?;
        let up = right.cross(forward);
        Self::new(eye, right, up, forward, yfov)
    }

    /// A camera placed by a node's world matrix (glTF: looks down local −Z, +Y up).
    pub fn from_matrix(world: &Mat4, yfov: f32) -> Result<Self, String> {
        let origin = Vec3A::from(world.w_axis.truncate());
        check_position("position", origin)?;
        let back = Vec3A::from(world.z_axis.truncate());
        let forward =
            (-back).try_normalize().ok_or_else(|| format!("its matrix's Z axis {back} is zero or not finite"))?;
        let up_hint = Vec3A::from(world.y_axis.truncate());
        let right = forward.cross(up_hint).try_normalize().ok_or_else(|| {
            format!("its matrix's Y axis {up_hint} is zero or parallel to its view direction {forward}")
        })?;
        let up = right.cross(forward);
        Self::new(origin, right, up, forward, yfov)
    }

    fn new(origin: Vec3A, right: Vec3A, up: Vec3A, forward: Vec3A, yfov: f32) -> Result<Self, String> {
        if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
            return Err(format!("its vertical field of view {}° is not between 0° and 180°", yfov.to_degrees()));
        }
        Ok(Self { origin, right, up, forward, tan_half_fov_y: (0.5 * yfov).tan() })
    }

    /// Where the camera is.
    pub fn position(&self) -> Vec3A {
        self.origin
    }

    /// The unit direction it looks in.
    pub fn forward(&self) -> Vec3A {
        self.forward
    }

    /// Turned about `pivot`: by `yaw` radians about the vertical `up` (unit), then by `pitch`
    /// about its own right axis (positive: the view turns up and the camera goes down). A
    /// pitch that would bring the view within ~8° of `up` is left out, so the view never
    /// flips. A point at the pivot stays where it was on the image.
    pub fn orbit(&self, pivot: Vec3A, up: Vec3A, yaw: f32, pitch: f32) -> Camera {
        let turn = |c: &Camera, q: Quat| Camera {
            origin: pivot + q * (c.origin - pivot),
            right: q * c.right,
            up: q * c.up,
            forward: q * c.forward,
            ..*c
        };
        let yawed = turn(self, Quat::from_axis_angle(up.into(), yaw));
        let pitched = turn(&yawed, Quat::from_axis_angle(yawed.right.into(), pitch));
        if pitched.forward.dot(up).abs() < 0.99 { pitched } else { yawed }
    }

    /// Moved by `dx` along its right and `dy` along its up, in world units.
    pub fn pan(&self, dx: f32, dy: f32) -> Camera {
        Camera { origin: self.origin + self.right * dx + self.up * dy, ..*self }
    }

    /// Moved `distance` along its view direction (backwards when negative).
    pub fn dolly(&self, distance: f32) -> Camera {
        Camera { origin: self.origin + self.forward * distance, ..*self }
    }

    /// The world-space height one pixel of an image `height` pixels high spans at `distance`
    /// in front of the camera: how far a drag of one pixel pans there.
    pub fn pixel_footprint(&self, distance: f32, height: u32) -> f32 {
        2.0 * distance * self.tan_half_fov_y / height.max(1) as f32
    }

    /// The primary ray through `pixel` of an image of `resolution` pixels (any size: the
    /// vertical field of view is kept) at sub-pixel offset `jitter ∈ [0,1)²`; unit direction.
    #[inline]
    pub fn ray(&self, pixel: UVec2, resolution: UVec2, jitter: Vec2) -> Ray {
        let res = resolution.as_vec2();
        let ndc = (pixel.as_vec2() + jitter) / res; // [0,1)², y down
        let aspect = res.x / res.y;
        let sx = (2.0 * ndc.x - 1.0) * self.tan_half_fov_y * aspect;
        let sy = (1.0 - 2.0 * ndc.y) * self.tan_half_fov_y;
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.origin, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_and_corners() {
        let res = UVec2::new(40, 30);
        let cam = Camera::look_at(Vec3A::new(0.0, 1.0, 4.0), Vec3A::new(0.0, 1.0, 0.0), Vec3A::Y, 0.6).unwrap();
        let c = cam.ray(UVec2::new(20, 15), res, Vec2::ZERO);
        assert!((c.dir - Vec3A::NEG_Z).length() < 1e-6);
        // Top edge of the image is yfov/2 above the axis.
        let top = cam.ray(UVec2::new(20, 0), res, Vec2::ZERO);
        assert!((top.dir.y.atan2(-top.dir.z) - 0.3).abs() < 1e-5);
        // Pixel (0,0) is top-left.
        let tl = cam.ray(UVec2::ZERO, res, Vec2::ZERO);
        assert!(tl.dir.x < 0.0 && tl.dir.y > 0.0);
        let e = Camera::look_at(Vec3A::ZERO, Vec3A::ZERO, Vec3A::Y, 0.6).unwrap_err();
        assert!(e.contains("is at the target"), "{e}");
        let e = Camera::look_at(Vec3A::ZERO, Vec3A::Y, Vec3A::Y, 0.6).unwrap_err();
        assert!(e.contains("parallel") && e.contains("[0, 1, 0]"), "{e}");
        let e = Camera::look_at(Vec3A::ZERO, Vec3A::X, Vec3A::Y, 3.5).unwrap_err();
        assert!(e.contains("200.5"), "{e}");
        let e = Camera::look_at(Vec3A::splat(f32::INFINITY), Vec3A::X, Vec3A::Y, 0.6).unwrap_err();
        assert!(e.contains("eye"), "{e}");
    }

    #[test]
    fn matrix_camera_matches_look_at() {
        let res = UVec2::new(8, 6);
        let m = Mat4::from_translation(glam::Vec3::new(0.0, 1.0, 4.4));
        let a = Camera::from_matrix(&m, 0.6).unwrap();
        let b = Camera::look_at(Vec3A::new(0.0, 1.0, 4.4), Vec3A::new(0.0, 1.0, 0.0), Vec3A::Y, 0.6).unwrap();
        let (ra, rb) = (a.ray(UVec2::new(1, 2), res, Vec2::splat(0.3)), b.ray(UVec2::new(1, 2), res, Vec2::splat(0.3)));
        assert!((ra.dir - rb.dir).length() < 1e-6);
    }

    #[test]
    fn orbit_keeps_the_pivot_at_the_centre_and_its_distance() {
        let res = UVec2::new(40, 30);
        let pivot = Vec3A::new(0.0, 1.0, 0.0);
        let cam = Camera::look_at(Vec3A::new(0.0, 1.0, 4.0), pivot, Vec3A::Y, 0.6).unwrap();
        let moved = cam.orbit(pivot, Vec3A::Y, 0.7, 0.3);
        assert!(((moved.position() - pivot).length() - 4.0).abs() < 1e-4);
        let centre = moved.ray(UVec2::new(20, 15), res, Vec2::ZERO);
        assert!((centre.dir - (pivot - moved.position()).normalize()).length() < 1e-5);
        assert!(moved.position().y < 1.0, "a positive pitch looks up from below");
        // Yaw alone keeps the height; a pitch past the vertical is dropped.
        assert!((cam.orbit(pivot, Vec3A::Y, 1.0, 0.0).position().y - 1.0).abs() < 1e-5);
        let steep = cam.orbit(pivot, Vec3A::Y, 0.0, 1.6);
        assert!((steep.position().y - 1.0).abs() < 1e-5, "{}", steep.position());
    }

    #[test]
    fn pan_and_dolly_move_along_the_camera_axes() {
        let cam = Camera::look_at(Vec3A::new(0.0, 1.0, 4.0), Vec3A::new(0.0, 1.0, 0.0), Vec3A::Y, 0.6).unwrap();
        let p = cam.pan(0.5, 0.25).dolly(1.0);
        assert!((p.position() - Vec3A::new(0.5, 1.25, 3.0)).length() < 1e-6);
        assert_eq!(p.forward(), cam.forward());
        // The top edge of a 30-pixel image at distance 4 is 4·tan(0.3) above the axis.
        assert!((cam.pixel_footprint(4.0, 30) * 15.0 - 4.0 * 0.3f32.tan()).abs() < 1e-5);
    }
}
