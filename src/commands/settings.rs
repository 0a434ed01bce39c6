//! The one place render settings are decided: what the command line asks
//! ([`RenderRequest`]) over what the scene file asks ([`RenderDefaults`]) over myriad's
//! defaults. Every command resolves through [`RenderRequest::resolve`].

use std::time::Duration;

use crate::error::{Error, Result};
use crate::film::AovSet;
use crate::math::UVec2;
use crate::render::{Budget, RenderSettings};
use crate::settings::{Clamp, LightSamplerKind, RenderDefaults};

/// Samples per pixel of `render` when neither the command line nor the scene says.
pub const DEFAULT_SPP: u32 = 64;
/// Samples per pixel of each `compare` run when neither the command line nor the scene says.
pub const COMPARE_DEFAULT_SPP: u32 = 16;
/// Scattering events when neither the command line nor the scene says (Cycles' default 8
/// bounces, like the reference renders).
pub const DEFAULT_MAX_DEPTH: u32 = 8;
/// The light sampler when neither the command line nor the scene names one: `cells`, which
/// is the tree under the 8 lights its tables take (`tools/equal_time.py`: it is never behind
/// the tree at equal time, up to 1.28× ahead on the Cornell grids and 1.25× on street.ron).
pub const DEFAULT_SAMPLER: LightSamplerKind = LightSamplerKind::Cells;
/// Whether paths are guided when neither the command line nor the scene says.
pub const DEFAULT_GUIDING: bool = false;
/// Whether light through smooth glass is solved for when neither the command line nor the
/// scene says.
pub const DEFAULT_CAUSTICS: bool = true;

/// Render settings as the command line gives them; `None` (and `false`) leave the choice to
/// the scene file, then to the defaults.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderRequest {
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Render for this long (whole passes) instead of a fixed spp; wins over any spp.
    pub time: Option<Duration>,
    /// Render samples `first..end` of every pixel (a part of a split render) instead.
    pub samples: Option<(u32, u32)>,
    /// Light sampler.
    pub sampler: Option<LightSamplerKind>,
    /// Random seed (`compare`: its runs use the seeds after it).
    pub seed: Option<u64>,
    /// Maximum scattering events.
    pub max_depth: Option<u32>,
    /// Direct lighting only: max depth 1, whatever else says.
    pub direct_only: bool,
    /// Sample clamping.
    pub clamp: Option<Clamp>,
    /// Path guiding.
    pub guiding: Option<bool>,
    /// Light through smooth glass solved for.
    pub caustics: Option<bool>,
}

/// Settings decided: every choice made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Samples per pixel or time.
    pub budget: Budget,
    /// Seed of every random number.
    pub seed: u64,
    /// Maximum scattering events.
    pub max_depth: u32,
    /// Light sampler.
    pub sampler: LightSamplerKind,
    /// Sample clamping.
    pub clamp: Clamp,
    /// Path guiding.
    pub guiding: bool,
    /// Light through smooth glass solved for.
    pub caustics: bool,
}

impl Resolved {
    /// The settings of a render with these choices of an image of `resolution` keeping `aovs`.
    pub fn render_settings(&self, resolution: UVec2, aovs: AovSet) -> RenderSettings {
        let Resolved { budget, seed, max_depth, clamp, guiding, caustics, .. } = *self;
        RenderSettings { budget, seed, max_depth, clamp, guiding, caustics, resolution, aovs }
    }
}

impl RenderRequest {
    /// Each setting from the command line, else the scene file, else the default;
    /// `default_spp` is the command's own ([`DEFAULT_SPP`], [`COMPARE_DEFAULT_SPP`]).
    pub fn resolve(&self, scene: &RenderDefaults, default_spp: u32) -> Result<Resolved> {
        let budget = match (self.time, self.spp.or(scene.spp)) {
            _ if let Some((a, b)) = self.samples => Budget::Samples(a, b),
            (Some(t), _) => Budget::Time(t),
            (None, Some(0)) => return Err(Error::Usage("--spp must be at least 1".into())),
            (None, spp) => Budget::Spp(spp.unwrap_or(default_spp)),
        };
        let max_depth = match self.max_depth.or(scene.max_depth) {
            _ if self.direct_only => 1,
            Some(0) => return Err(Error::Usage("--max-depth must be at least 1".into())),
            depth => depth.unwrap_or(DEFAULT_MAX_DEPTH),
        };
        Ok(Resolved {
            budget,
            seed: self.seed.or(scene.seed).unwrap_or(0),
            max_depth,
            sampler: self.sampler.or(scene.sampler).unwrap_or(DEFAULT_SAMPLER),
            clamp: self.clamp.or(scene.clamp).unwrap_or(Clamp::OFF),
            guiding: self.guiding.or(scene.guiding).unwrap_or(DEFAULT_GUIDING),
            caustics: self.caustics.or(scene.caustics).unwrap_or(DEFAULT_CAUSTICS),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_wins_over_the_scene_which_wins_over_the_defaults() {
        let scene = RenderDefaults {
            spp: Some(8),
            max_depth: Some(3),
            sampler: Some(LightSamplerKind::Power),
            seed: Some(7),
            clamp: None,
            guiding: None,
            caustics: Some(false),
        };
        let none = RenderRequest::default();
        let from_scene = none.resolve(&scene, DEFAULT_SPP).unwrap();
        assert_eq!(
            from_scene,
            Resolved {
                budget: Budget::Spp(8),
                seed: 7,
                max_depth: 3,
                sampler: LightSamplerKind::Power,
                clamp: Clamp::OFF,
                guiding: DEFAULT_GUIDING,
                caustics: false,
            }
        );
        let defaults = none.resolve(&RenderDefaults::default(), COMPARE_DEFAULT_SPP).unwrap();
        assert_eq!(
            defaults,
            Resolved {
                budget: Budget::Spp(16),
                seed: 0,
                max_depth: DEFAULT_MAX_DEPTH,
                sampler: DEFAULT_SAMPLER,
                clamp: Clamp::OFF,
                guiding: DEFAULT_GUIDING,
                caustics: DEFAULT_CAUSTICS,
            }
        );
        let asked = RenderRequest {
            spp: Some(2),
            sampler: Some(LightSamplerKind::Uniform),
            seed: Some(1),
            direct_only: true,
            ..Default::default()
        };
        let got = asked.resolve(&scene, DEFAULT_SPP).unwrap();
        assert_eq!(
            got,
            Resolved {
                budget: Budget::Spp(2),
                seed: 1,
                max_depth: 1,
                sampler: LightSamplerKind::Uniform,
                clamp: Clamp::OFF,
                guiding: DEFAULT_GUIDING,
                caustics: false,
            }
        );
        let timed = RenderRequest { time: Some(Duration::from_secs(3)), ..Default::default() };
        assert_eq!(timed.resolve(&scene, DEFAULT_SPP).unwrap().budget, Budget::Time(Duration::from_secs(3)));
        assert!(RenderRequest { spp: Some(0), ..Default::default() }.resolve(&scene, 1).is_err());
        assert!(RenderRequest { max_depth: Some(0), ..Default::default() }.resolve(&scene, 1).is_err());
    }
}
