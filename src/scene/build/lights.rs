//! The lights a description lists besides its emissive meshes, checked and converted.

use super::validate::{check_color, check_point};
use crate::error::{Error, Result};
use crate::light::{AreaEmission, DistantLight, EnvironmentLight, Light, PointLight, QuadLight, SpotLight};
use crate::limits::MAX_POWER;
use crate::scene::description::LightDesc;

/// Light `i` of `file`, checked: finite positions in range, non-negative colours, a
/// direction, cone angles in order, a non-zero area, a power myriad can hold.
pub(super) fn light(file: &str, i: usize, desc: &LightDesc) -> Result<Light> {
    let what = format!("light {i} '{}'", desc.name());
    let direction = |d: crate::math::Vec3A| {
        d.try_normalize().ok_or_else(|| Error::scene(file, &what, format!("direction {d} must be a non-zero vector")))
    };
    let light = match desc {
        LightDesc::Point { position, intensity, .. } => {
            check_point(file, &what, "position", *position)?;
            check_color(file, &what, "intensity", *intensity, None)?;
            Light::Point(PointLight { position: *position, intensity: *intensity })
        }
        LightDesc::Spot { position, direction: d, intensity, inner_angle, outer_angle, curve, .. } => {
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
            Light::Spot(SpotLight {
                position: *position,
                direction,
                intensity: *intensity,
                cos_inner: inner_angle.cos(),
                cos_outer: outer_angle.cos(),
                curve: *curve,
            })
        }
        LightDesc::Directional { direction: d, irradiance, .. } => {
            check_color(file, &what, "irradiance", *irradiance, None)?;
            Light::Distant(DistantLight { direction: direction(*d)?, irradiance: *irradiance })
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
