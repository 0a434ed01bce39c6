//! The lights a description lists besides its emissive meshes, checked and converted.

use super::validate::{check_color, check_point};
use crate::error::{Error, Result};
use crate::light::{
    AreaEmission, AreaLight, DistantLight, EnvironmentLight, Light, PointLight, QuadLight, SphereLight, SpotCone,
    SpotLight, SunLight,
};
use crate::limits::{MAX_COORDINATE, MAX_POWER};
use crate::math::{Rgb, Vec3A};
use crate::scene::description::{LampShape, LightDesc};

/// Light `i` of `file`, checked: finite positions in range, non-negative colours, a
/// direction, cone angles in order, a non-zero area, a power myriad can hold.
pub(super) fn light(file: &str, i: usize, desc: &LightDesc) -> Result<Light> {
    let what = format!("light {i} '{}'", desc.name());
    let direction = |d: crate::math::Vec3A| {
        d.try_normalize().ok_or_else(|| Error::scene(file, &what, format!("direction {d} must be a non-zero vector")))
    };
    let light = match desc {
        LightDesc::Point { position, intensity, lamp, .. } => {
            check_point(file, &what, "position", *position)?;
            check_color(file, &what, "intensity", *intensity, None)?;
            match lamp {
                Some(shape) => sphere(file, &what, *position, *intensity, shape, None)?,
                None => Light::Point(PointLight { position: *position, intensity: *intensity }),
            }
        }
        LightDesc::Spot { position, direction: d, intensity, inner_angle, outer_angle, curve, lamp, .. } => {
            check_point(file, &what, "position", *position)?;
            check_color(file, &what, "intensity", *intensity, None)?;
            let direction = direction(*d)?;
            if !(*outer_angle > 0.0
                && *outer_angle <= std::f32::consts::PI
                && *inner_angle >= 0.0
                && inner_angle <= outer_angle)
            {
                return Err(Error::scene(
                    file,
                    what,
                    format!("cone angles need 0 ≤ inner ({inner_angle}) ≤ outer ({outer_angle}) ≤ π, outer > 0"),
                ));
            }
            let spot = SpotLight {
                position: *position,
                direction,
                intensity: *intensity,
                cos_inner: inner_angle.cos(),
                cos_outer: outer_angle.cos(),
                curve: *curve,
            };
            match lamp {
                Some(shape) => sphere(file, &what, *position, *intensity, shape, Some(spot.cone()))?,
                None => Light::Spot(spot),
            }
        }
        LightDesc::Directional { direction: d, irradiance, angle, camera_visible, .. } => {
            check_color(file, &what, "irradiance", *irradiance, None)?;
            if !(*angle >= 0.0 && *angle <= std::f32::consts::PI) {
                return Err(Error::scene(file, what, format!("angle {angle} rad must be between 0 and π (180°)")));
            }
            let direction = direction(*d)?;
            match SunLight::new(direction, *irradiance, *angle) {
                Some(sun) => Light::Sun(SunLight { camera_visible: *camera_visible, ..sun }),
                None => Light::Distant(DistantLight { direction, irradiance: *irradiance }),
            }
        }
        LightDesc::Area { center, u, v, ellipse, radiance, spread, camera_visible, .. } => {
            check_point(file, &what, "centre", *center)?;
            check_point(file, &what, "corner", *center + *u + *v)?;
            check_color(file, &what, "radiance", *radiance, None)?;
            if !(*spread >= 0.0 && *spread <= std::f32::consts::PI) {
                return Err(Error::scene(file, what, format!("spread {spread} rad must be between 0 and π (180°)")));
            }
            let lamp = AreaLight::new(*center, *u, *v, *ellipse, *radiance, *spread).ok_or_else(|| {
                Error::scene(file, &what, format!("has zero area: its sides {u} and {v} are parallel or zero"))
            })?;
            Light::Area(AreaLight { camera_visible: *camera_visible, ..lamp })
        }
        LightDesc::Quad { corner, edge1, edge2, radiance, two_sided, .. } => {
            check_point(file, &what, "corner", *corner)?;
            check_point(file, &what, "far corner", *corner + *edge1 + *edge2)?;
            check_color(file, &what, "radiance", *radiance, None)?;
            let emission = AreaEmission { radiance: *radiance, two_sided: *two_sided };
            let q = QuadLight::new(*corner, *edge1, *edge2, emission).ok_or_else(|| {
                Error::scene(file, &what, format!("has zero area: its edges {edge1} and {edge2} are parallel or zero"))
            })?;
            Light::Quad(q)
        }
    };
    check_power(file, &what, &light, 0.0)?;
    Ok(light)
}

/// A point or spot lamp of `shape` at `center` (the spot's `cone`), its radius checked.
fn sphere(
    file: &str,
    what: &str,
    center: Vec3A,
    intensity: Rgb,
    shape: &LampShape,
    cone: Option<SpotCone>,
) -> Result<Light> {
    let r = shape.radius;
    if !(r > 0.0 && r <= MAX_COORDINATE) {
        return Err(Error::scene(
            file,
            what,
            format!("radius {r} must be positive (0: a point) and at most {MAX_COORDINATE:e} m"),
        ));
    }
    let lamp = SphereLight::new(center, r, intensity, shape.model, cone);
    Ok(Light::Sphere(SphereLight { camera_visible: shape.camera_visible, ..lamp }))
}

/// The environment, checked: a non-negative finite radiance (or map factor) and a power
/// myriad can hold over the scene's disc of `scene_radius`.
pub(super) fn environment(file: &str, name: &str, env: &EnvironmentLight, scene_radius: f32) -> Result<Light> {
    check_color(file, name, "radiance", env.radiance, None)?;
    if !env.rotation.is_finite() {
        return Err(Error::scene(file, name, format!("rotation {} is not finite", env.rotation)));
    }
    let light = Light::Environment(env.clone());
    check_power(file, name, &light, scene_radius)?;
    Ok(light)
}

/// An error when `light` emits more than [`MAX_POWER`] (directional lights: over a disc of
/// `scene_radius`).
pub(super) fn check_power(file: &str, what: &str, light: &Light, scene_radius: f32) -> Result<()> {
    let power = light.power(scene_radius);
    if power <= MAX_POWER {
        return Ok(());
    }
    Err(Error::scene(
        file,
        what,
        format!("emits {power:e} W, beyond myriad's limit of {MAX_POWER:e} W; its intensity or size is out of scale"),
    ))
}
