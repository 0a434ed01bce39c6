//! The viewer's controls: which key does what, and how mouse drags move the camera.

use minifb::Key;

use crate::camera::Camera;
use crate::math::Vec3A;
use crate::settings::LightSamplerKind;

/// Exposure change per key press, in stops.
pub const EXPOSURE_STEP: f32 = 0.5;
/// Orbit angle per pixel of mouse motion, in radians.
const ORBIT_PER_PIXEL: f32 = 0.01;
/// Share of the distance to the pivot one wheel notch moves the camera.
const DOLLY_PER_NOTCH: f32 = 0.1;

/// The keys, as the status bar lists them.
pub const KEYS: [&str; 8] =
    ["1-7 sampler", "G guiding", "C caustics", "+/- exposure", "E error", "S save", "R reset", "Esc quit"];

/// What a key asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Switch to this light sampler (restarts the accumulation).
    Sampler(LightSamplerKind),
    /// Turn path guiding on or off (restarts the accumulation).
    ToggleGuiding,
    /// Turn the connections through smooth glass on or off (restarts the accumulation).
    ToggleCaustics,
    /// Change the exposure by this many stops (display only).
    Exposure(f32),
    /// Show the false-colour relative error against the reference, or the render again.
    ToggleError,
    /// Save the image so far as EXR.
    Save,
    /// Put the camera back where the scene has it.
    ResetCamera,
    /// Close the viewer.
    Quit,
}

/// The action of a key: 1–7 pick the samplers in the order `--sampler` lists them.
pub fn action(key: Key) -> Option<Action> {
    let digits = [Key::Key1, Key::Key2, Key::Key3, Key::Key4, Key::Key5, Key::Key6, Key::Key7];
    if let Some(i) = digits.iter().position(|&k| k == key) {
        return LightSamplerKind::EVERY.get(i).map(|&s| Action::Sampler(s));
    }
    Some(match key {
        Key::Equal | Key::NumPadPlus => Action::Exposure(EXPOSURE_STEP),
        Key::Minus | Key::NumPadMinus => Action::Exposure(-EXPOSURE_STEP),
        Key::E => Action::ToggleError,
        Key::G => Action::ToggleGuiding,
        Key::C => Action::ToggleCaustics,
        Key::S => Action::Save,
        Key::R => Action::ResetCamera,
        Key::Escape | Key::Q => Action::Quit,
        _ => return None,
    })
}

/// Mouse navigation about a pivot in front of the camera: left drag orbits about the world's
/// vertical (+Y, glTF's up), right or shift-left drag pans, the wheel dollies towards the pivot.
#[derive(Clone, Copy, Debug)]
pub struct Navigation {
    /// Where the camera started (what [`Action::ResetCamera`] goes back to).
    pub home: Camera,
    pivot: Vec3A,
    home_pivot: Vec3A,
    height: u32,
}

impl Navigation {
    /// Navigation of `camera` over an image `height` pixels high, pivoting about the point
    /// in front of it level with the scene's centre (at least a twentieth of the scene's
    /// radius away).
    pub fn new(camera: Camera, center: Vec3A, radius: f32, height: u32) -> Self {
        let distance = (center - camera.position()).dot(camera.forward()).max(0.05 * radius.max(1e-3));
        let pivot = camera.position() + camera.forward() * distance;
        Self { home: camera, pivot, home_pivot: pivot, height }
    }

    /// Back to the scene's camera.
    pub fn reset(&mut self) -> Camera {
        self.pivot = self.home_pivot;
        self.home
    }

    /// `camera` orbited by a drag of (dx, dy) pixels (right: the scene turns right).
    pub fn orbit(&self, camera: &Camera, dx: f32, dy: f32) -> Camera {
        camera.orbit(self.pivot, Vec3A::Y, -dx * ORBIT_PER_PIXEL, dy * ORBIT_PER_PIXEL)
    }

    /// `camera` panned by a drag of (dx, dy) pixels: the point at the pivot follows the mouse.
    pub fn pan(&mut self, camera: &Camera, dx: f32, dy: f32) -> Camera {
        let step = camera.pixel_footprint((self.pivot - camera.position()).length(), self.height);
        let moved = camera.pan(-dx * step, dy * step);
        self.pivot += moved.position() - camera.position();
        moved
    }

    /// `camera` dollied by `notches` of the wheel (positive: closer to the pivot, never past it).
    pub fn dolly(&self, camera: &Camera, notches: f32) -> Camera {
        let distance = (self.pivot - camera.position()).length();
        let step = (distance * DOLLY_PER_NOTCH * notches).min(0.9 * distance);
        camera.dolly(step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{UVec2, Vec2};

    #[test]
    fn number_keys_pick_the_samplers_in_command_line_order() {
        assert_eq!(action(Key::Key1), Some(Action::Sampler(LightSamplerKind::All)));
        assert_eq!(action(Key::Key5), Some(Action::Sampler(LightSamplerKind::Tree)));
        assert_eq!(action(Key::Key6), Some(Action::Sampler(LightSamplerKind::Learned)));
        assert_eq!(action(Key::Key7), Some(Action::Sampler(LightSamplerKind::Cells)));
        assert_eq!(action(Key::Minus), Some(Action::Exposure(-EXPOSURE_STEP)));
        assert_eq!(action(Key::G), Some(Action::ToggleGuiding));
        assert_eq!(action(Key::C), Some(Action::ToggleCaustics));
        assert_eq!(action(Key::Escape), Some(Action::Quit));
        assert_eq!(action(Key::Z), None);
    }

    #[test]
    fn drags_orbit_about_the_pivot_pan_with_the_mouse_and_dolly_stops_short() {
        let eye = Vec3A::new(0.0, 1.0, 4.0);
        let camera = Camera::look_at(eye, Vec3A::new(0.0, 1.0, 0.0), Vec3A::Y, 0.6).unwrap();
        let mut nav = Navigation::new(camera, Vec3A::new(0.3, 1.0, 0.0), 2.0, 30);
        let turned = nav.orbit(&camera, 50.0, 0.0);
        assert!(((turned.position() - Vec3A::new(0.0, 1.0, 0.0)).length() - 4.0).abs() < 1e-4);
        let panned = nav.pan(&camera, 15.0, 0.0);
        // Half the image's height of drag moves the camera by half the view's height there.
        assert!((panned.position().x + 4.0 * 0.3f32.tan()).abs() < 1e-4, "{}", panned.position());
        let centre = panned.ray(UVec2::new(20, 15), UVec2::new(40, 30), Vec2::ZERO).dir;
        assert!((centre - panned.forward()).length() < 1e-5);
        let close = nav.dolly(&panned, 100.0);
        assert!(((close.position() - panned.position()).length() - 3.6).abs() < 1e-4);
        assert_eq!(nav.reset().position(), eye);
    }
}
