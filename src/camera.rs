//! The perspective camera: (pixel, jitter[, lens point]) → primary ray.
//!
//! Owns: the camera model shared by every loader (RON look-at, glTF node matrix, the Blender
//! add-on). The image plane follows glTF: the camera looks down its local −Z with +Y up. The
//! field of view spans one dimension, its [`Fit`]: the height by default (glTF's `yfov`,
//! kept when the aspect ratio changes; docs/conventions.md), or the width, or the larger of
//! the two (Blender's sensor fit). The view may be shifted (Blender's lens shift, in units of
//! the fitted dimension) and focused through a thin lens (depth of field: a disk aperture, a
//! focal plane at the focus distance, as Cycles has them). Pixel (0,0) is the top-left
//! corner; the pixel filter is a 1-pixel box, as in the Cycles references.

use crate::geometry::Ray;
use crate::math::{Mat4, UVec2, Vec2, Vec3A};
use glam::Quat;

/// A camera position must be finite.
fn check_position(name: &str, p: Vec3A) -> Result<(), String> {
    use crate::limits::MAX_COORDINATE;
    if p.is_finite() && p.abs().max_element() <= MAX_COORDINATE {
        Ok(())
    } else {
        Err(format!(
            "its {name} {p} is not finite or lies beyond ±{MAX_COORDINATE} m (as no vertex may); scale the scene down"
        ))
    }
}

/// Which image dimension the field of view spans.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Fit {
    /// The height (glTF's `yfov`).
    #[default]
    Vertical,
    /// The width.
    Horizontal,
    /// The larger of the two (Blender's Auto sensor fit).
    Auto,
}

/// A thin lens: the aperture disk and the distance of the plane in focus.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    /// Radius of the aperture, metres (Blender: focal length / (2 · f-stop)).
    pub aperture_radius: f32,
    /// Distance of the focal plane along the view axis, metres.
    pub focus_distance: f32,
}

/// Where the camera sees a point ([`Camera::project`]).
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    /// The pixel it falls in.
    pub pixel: UVec2,
    /// Unit direction from the point to the camera.
    pub to_camera: Vec3A,
    /// Distance from the point to the camera.
    pub distance: f32,
    /// The density with which a camera ray, its pixel and jitter uniform over the image,
    /// leaves towards the point, per unit solid angle (the pinhole's importance).
    pub importance: f32,
}

/// A perspective camera.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    origin: Vec3A,
    right: Vec3A,
    up: Vec3A,
    forward: Vec3A,
    /// tan of half the field of view along the fitted dimension.
    tan_half_fov: f32,
    fit: Fit,
    /// The view's shift, in units of the fitted dimension's extent (x right, y up).
    shift: Vec2,
    lens: Option<ThinLens>,
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
        Ok(Self {
            origin,
            right,
            up,
            forward,
            tan_half_fov: (0.5 * yfov).tan(),
            fit: Fit::Vertical,
            shift: Vec2::ZERO,
            lens: None,
        })
    }

    /// The same camera with its field of view spanning `fit` and the view shifted by `shift`
    /// (fractions of the fitted dimension's extent; positive: right and up). An error says
    /// what is wrong.
    pub fn with_projection(self, fit: Fit, shift: Vec2) -> Result<Self, String> {
        if !shift.is_finite() || shift.abs().max_element() > 100.0 {
            return Err(format!("its shift {shift} is not a finite shift within ±100"));
        }
        Ok(Self { fit, shift, ..self })
    }

    /// The same camera focused through `lens`. An error says what is wrong.
    pub fn with_lens(self, lens: ThinLens) -> Result<Self, String> {
        let ThinLens { aperture_radius: r, focus_distance: d } = lens;
        if !(r >= 0.0 && r.is_finite() && d > 0.0 && d.is_finite()) {
            return Err(format!(
                "its aperture radius {r} and focus distance {d} must be finite, the radius ≥ 0 and the distance > 0"
            ));
        }
        Ok(Self { lens: (r > 0.0).then_some(lens), ..self })
    }

    /// Whether rays start across a lens aperture (and [`ray_through_lens`](Self::ray_through_lens)
    /// wants two numbers for it).
    #[inline]
    pub fn has_lens(&self) -> bool {
        self.lens.is_some()
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
        2.0 * distance * self.tan_half_fov / height.max(1) as f32
    }

    /// tan of half the horizontal and vertical fields of view of an image of `res` pixels.
    #[inline]
    fn tan_half_fovs(&self, res: Vec2) -> Vec2 {
        let horizontal = match self.fit {
            Fit::Vertical => false,
            Fit::Horizontal => true,
            Fit::Auto => res.x > res.y,
        };
        if horizontal {
            Vec2::new(self.tan_half_fov, self.tan_half_fov * res.y / res.x)
        } else {
            Vec2::new(self.tan_half_fov * res.x / res.y, self.tan_half_fov)
        }
    }

    /// The direction, in camera space (x right, y up, z forward, unnormalised with z = 1),
    /// through `pixel` + `jitter` of an image of `resolution`.
    #[inline]
    fn camera_direction(&self, pixel: UVec2, resolution: UVec2, jitter: Vec2) -> Vec2 {
        let res = resolution.as_vec2();
        let ndc = (pixel.as_vec2() + jitter) / res; // [0,1)², y down
        let tan = self.tan_half_fovs(res);
        // A shift moves the view by a fraction of the fitted dimension's whole extent.
        let offset = 2.0 * self.tan_half_fov * self.shift;
        Vec2::new((2.0 * ndc.x - 1.0) * tan.x, (1.0 - 2.0 * ndc.y) * tan.y) + offset
    }

    /// The primary ray through `pixel` of an image of `resolution` pixels (any size: the
    /// fitted field of view is kept) at sub-pixel offset `jitter ∈ [0,1)²`, from the centre
    /// of the lens; unit direction.
    #[inline]
    pub fn ray(&self, pixel: UVec2, resolution: UVec2, jitter: Vec2) -> Ray {
        let s = self.camera_direction(pixel, resolution, jitter);
        let dir = (self.forward + self.right * s.x + self.up * s.y).normalize();
        Ray::new(self.origin, dir)
    }

    /// Where the pinhole camera sees world point `p` on an image of `resolution` (`None`:
    /// behind it or outside the image): the inverse of [`ray`](Self::ray), for light paths
    /// that end at the camera.
    #[inline]
    pub fn project(&self, p: Vec3A, resolution: UVec2) -> Option<Projection> {
        let d = p - self.origin;
        let z = d.dot(self.forward);
        if !(z > 0.0) {
            return None;
        }
        let res = resolution.as_vec2();
        let tan = self.tan_half_fovs(res);
        let s = Vec2::new(d.dot(self.right), d.dot(self.up)) / z - 2.0 * self.tan_half_fov * self.shift;
        let ndc = Vec2::new(0.5 * (s.x / tan.x + 1.0), 0.5 * (1.0 - s.y / tan.y));
        if !(ndc.x >= 0.0 && ndc.x < 1.0 && ndc.y >= 0.0 && ndc.y < 1.0) {
            return None;
        }
        let pixel = (ndc * res).as_uvec2().min(resolution - 1);
        let distance = d.length();
        let cos = z / distance;
        // Camera rays cross the plane z = 1 uniformly over the image's 4·tan.x·tan.y: per
        // unit solid angle that is 1 / (area · cos³θ).
        let importance = 1.0 / (4.0 * tan.x * tan.y * cos * cos * cos);
        Some(Projection { pixel, to_camera: -d / distance, distance, importance })
    }

    /// [`ray`](Self::ray) from the point `lens_u ∈ [0,1)²` picks uniformly on the aperture
    /// disk, towards where the pinhole ray meets the focal plane (Cycles' thin lens); the
    /// pinhole ray without a lens.
    #[inline]
    pub fn ray_through_lens(&self, pixel: UVec2, resolution: UVec2, jitter: Vec2, lens_u: Vec2) -> Ray {
        let Some(lens) = self.lens else { return self.ray(pixel, resolution, jitter) };
        let s = self.camera_direction(pixel, resolution, jitter);
        // The pinhole direction has z = 1: it meets the focal plane at focus_distance · (s, 1).
        let focus = lens.focus_distance * (self.forward + self.right * s.x + self.up * s.y);
        let a = crate::math::warp::square_to_disk_concentric(lens_u) * lens.aperture_radius;
        let start = self.right * a.x + self.up * a.y;
        Ray::new(self.origin + start, (focus - start).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_camera_beyond_the_largest_coordinate_is_refused() {
        // Rays from there are beyond what the tracers take (Embree asserts below 1.8·10¹⁸).
        let far = Vec3A::new(3e19, 0.0, 0.0);
        let e = Camera::look_at(far, Vec3A::ZERO, Vec3A::Y, 0.8).unwrap_err();
        assert!(e.contains("beyond"), "{e}");
        let e = Camera::from_matrix(&Mat4::from_translation(glam::Vec3::new(0.0, -2e12, 0.0)), 0.8).unwrap_err();
        assert!(e.contains("beyond"), "{e}");
        assert!(Camera::look_at(Vec3A::new(0.0, 1.0, 5.0), Vec3A::ZERO, Vec3A::Y, 0.8).is_ok());
    }

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
    fn projection_finds_the_pixel_a_ray_came_from_and_its_density_integrates_to_one() {
        let res = UVec2::new(40, 30);
        let cam = Camera::look_at(Vec3A::new(0.5, 1.0, 4.0), Vec3A::new(0.0, 1.2, 0.0), Vec3A::Y, 0.9)
            .unwrap()
            .with_projection(Fit::Auto, Vec2::new(0.1, -0.05))
            .unwrap();
        // Each pixel's ray, followed 3 m, projects back into that pixel.
        let mut integral = 0.0f64;
        for y in 0..res.y {
            for x in 0..res.x {
                let px = UVec2::new(x, y);
                let r = cam.ray(px, res, Vec2::splat(0.5));
                let p = cam.project(r.origin + 3.0 * r.dir, res).expect("in view");
                assert_eq!(p.pixel, px);
                assert!((p.to_camera + r.dir).length() < 1e-5 && (p.distance - 3.0).abs() < 1e-4);
                // Σ density × the pixel's solid angle (its corners' rays) ≈ 1.
                let corner = |dx: f32, dy: f32| cam.ray(px, res, Vec2::new(dx, dy)).dir;
                let (a, b, c) = (corner(0.0, 0.0), corner(1.0, 0.0), corner(0.0, 1.0));
                integral += (p.importance * (b - a).cross(c - a).length()) as f64;
            }
        }
        assert!((integral - 1.0).abs() < 0.01, "{integral}");
        assert!(cam.project(cam.position() - cam.forward(), res).is_none(), "behind the camera");
        assert!(cam.project(cam.position() + cam.forward() + 10.0 * Vec3A::X, res).is_none(), "beside the image");
    }

    #[test]
    fn the_field_of_view_spans_the_fitted_dimension_and_a_shift_moves_the_view() {
        let look = || Camera::look_at(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 0.6).unwrap();
        let angle_x = |r: &Ray| r.dir.x.atan2(-r.dir.z);
        let angle_y = |r: &Ray| r.dir.y.atan2(-r.dir.z);
        let (wide, tall) = (UVec2::new(40, 20), UVec2::new(20, 40));
        // Horizontal: the left edge is half the field of view off the axis.
        let h = look().with_projection(Fit::Horizontal, Vec2::ZERO).unwrap();
        assert!((angle_x(&h.ray(UVec2::new(0, 10), wide, Vec2::new(0.0, 0.5))) + 0.3).abs() < 1e-5);
        // Auto: the larger dimension, whichever it is.
        let a = look().with_projection(Fit::Auto, Vec2::ZERO).unwrap();
        assert!((angle_x(&a.ray(UVec2::new(0, 10), wide, Vec2::new(0.0, 0.5))) + 0.3).abs() < 1e-5);
        assert!((angle_y(&a.ray(UVec2::new(10, 0), tall, Vec2::new(0.5, 0.0))) - 0.3).abs() < 1e-5);
        // A shift of 0.1 moves the centre by a tenth of the fitted (larger) extent, in x and in y.
        let s = look().with_projection(Fit::Auto, Vec2::new(0.1, 0.1)).unwrap();
        let c = s.ray(UVec2::new(20, 10), wide, Vec2::ZERO);
        let extent = 2.0 * 0.3f32.tan();
        assert!((c.dir.x / -c.dir.z - 0.1 * extent).abs() < 1e-5 && (c.dir.y / -c.dir.z - 0.1 * extent).abs() < 1e-5);
        assert!(look().with_projection(Fit::Auto, Vec2::new(f32::NAN, 0.0)).is_err());
    }

    #[test]
    fn rays_through_the_lens_meet_on_the_focal_plane() {
        let lens = ThinLens { aperture_radius: 0.05, focus_distance: 3.0 };
        let cam = Camera::look_at(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 0.6).unwrap().with_lens(lens).unwrap();
        assert!(cam.has_lens());
        let (pixel, res, jitter) = (UVec2::new(7, 3), UVec2::new(20, 10), Vec2::splat(0.5));
        let pinhole = cam.ray(pixel, res, jitter);
        let focus = pinhole.at(3.0 / -pinhole.dir.z);
        for k in 0..16 {
            let u = Vec2::new((k as f32 * 0.618).fract(), (k as f32 * 0.382 + 0.2).fract());
            let r = cam.ray_through_lens(pixel, res, jitter, u);
            assert!(r.origin.z == 0.0 && r.origin.length() <= 0.05 + 1e-6, "{}", r.origin);
            let at = r.at((3.0 - r.origin.z) / -r.dir.z);
            assert!((at - focus).length() < 1e-4, "{at} vs {focus}");
        }
        let bad = ThinLens { aperture_radius: -1.0, focus_distance: 3.0 };
        assert!(Camera::look_at(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 0.6).unwrap().with_lens(bad).is_err());
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
