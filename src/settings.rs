//! What a user can ask a render for by name, wherever they ask it: the light sampler's
//! name ([`LightSamplerKind`]) and the render settings a scene file may carry
//! ([`RenderDefaults`]). The command line's requests and their resolution against these
//! (command line, then scene file, then myriad's defaults) are `commands::settings`.
//!
//! Owns names and plain values only, so that the scene format, the samplers and the
//! commands can all use them without depending on one another.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The light-selection strategies the `--sampler` switch and a scene's `render.sampler` name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LightSamplerKind {
    /// Every light at every shading point, one shadow ray each (the baseline of the
    /// predecessor project's report; O(n)).
    All,
    /// One light, uniformly at random.
    Uniform,
    /// One light, with probability proportional to its emitted power.
    Power,
    /// One light, from a CDF over every light's importance at the shading point (O(n)).
    Local,
    /// One light, by descending a light BVH with the same importance (O(log n)).
    Tree,
    /// One light, from a table per cell of space of `local`'s importances (a look-up per
    /// choice; over more than 1024 lights, at diffuse points a table of the tree's clusters and
    /// the tree below, at glossy ones the tree;
    /// the tree under 8 lights and in cells next to lights).
    Cells,
    /// The light BVH, its first levels reweighted per region of the scene by how much of
    /// each cluster's light earlier passes saw arrive (occlusion learned).
    Learned,
}

impl LightSamplerKind {
    /// Every sampler, in the order the command line lists them.
    pub const EVERY: [LightSamplerKind; 7] = [
        LightSamplerKind::All,
        LightSamplerKind::Uniform,
        LightSamplerKind::Power,
        LightSamplerKind::Local,
        LightSamplerKind::Tree,
        LightSamplerKind::Learned,
        LightSamplerKind::Cells,
    ];

    /// The name used on the command line, in scene files and in file headers.
    pub fn name(self) -> &'static str {
        match self {
            LightSamplerKind::All => "all",
            LightSamplerKind::Uniform => "uniform",
            LightSamplerKind::Power => "power",
            LightSamplerKind::Local => "local",
            LightSamplerKind::Tree => "tree",
            LightSamplerKind::Learned => "learned",
            LightSamplerKind::Cells => "cells",
        }
    }
}

impl fmt::Display for LightSamplerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for LightSamplerKind {
    type Err = String;

    /// A sampler by its [`name`](Self::name); the error lists the names there are.
    fn from_str(s: &str) -> Result<Self, String> {
        Self::EVERY.into_iter().find(|k| k.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Self::EVERY.iter().map(|k| k.name()).collect();
            format!("'{s}' is not a light sampler (there are: {})", names.join(", "))
        })
    }
}

/// Cycles' sample clamping ("Clamp Direct" and "Clamp Indirect"): a light contribution whose
/// channels sum to more than its limit is scaled down to the limit. `direct` limits light that
/// reaches the camera after at most one scattering event (next-event estimation at the first
/// surface, emitters seen directly or in one bounce), `indirect` the rest; 0 is no limit. It
/// darkens fireflies and so biases the picture: off unless asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct Clamp {
    /// Limit on direct light's channel sum; 0: none.
    pub direct: f32,
    /// Limit on indirect light's channel sum; 0: none.
    pub indirect: f32,
}

impl Clamp {
    /// No clamping.
    pub const OFF: Clamp = Clamp { direct: 0.0, indirect: 0.0 };

    /// Whether it limits anything.
    pub fn is_on(&self) -> bool {
        self.direct > 0.0 || self.indirect > 0.0
    }

    /// The limit for indirect light (`true`) or direct light; 0 is none.
    #[inline]
    pub fn limit(&self, indirect: bool) -> f32 {
        if indirect { self.indirect } else { self.direct }
    }

    /// An error unless both limits are finite and not negative.
    pub fn check(&self) -> Result<(), String> {
        for (what, v) in [("direct", self.direct), ("indirect", self.indirect)] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(format!("the {what} clamp must be a finite number ≥ 0 (0 = off), not {v}"));
            }
        }
        Ok(())
    }
}

impl fmt::Display for Clamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_on() { write!(f, "{},{}", self.direct, self.indirect) } else { f.write_str("off") }
    }
}

impl FromStr for Clamp {
    type Err = String;

    /// `INDIRECT` (direct light unclamped, as Blender's default) or `DIRECT,INDIRECT`; `off`.
    fn from_str(s: &str) -> Result<Self, String> {
        let number = |t: &str| {
            t.trim().parse::<f32>().map_err(|_| format!("'{t}' is not a number: give INDIRECT or DIRECT,INDIRECT"))
        };
        let c = match s.split_once(',') {
            _ if s == "off" => Clamp::OFF,
            Some((d, i)) => Clamp { direct: number(d)?, indirect: number(i)? },
            None => Clamp { direct: 0.0, indirect: number(s)? },
        };
        c.check().map(|()| c)
    }
}

/// A switch's name as options and headers write it: `on` or `off`.
pub fn on_off(on: bool) -> &'static str {
    if on { "on" } else { "off" }
}

/// Render settings a scene file may carry (its `render: (...)` block); `None` leaves the
/// choice to the command line, then to myriad's default. Zeros are refused by the loader.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDefaults {
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Maximum scattering events (1 = direct lighting only).
    pub max_depth: Option<u32>,
    /// Light sampler: `all`, `uniform`, `power`, `local`, `tree`, `learned` or `cells`.
    pub sampler: Option<LightSamplerKind>,
    /// Random seed.
    pub seed: Option<u64>,
    /// Sample clamping, e.g. `clamp: (indirect: 10)`; none by default.
    pub clamp: Option<Clamp>,
    /// Path guiding, `true` or `false`.
    pub guiding: Option<bool>,
    /// Caustics solved for, `true` or `false`: light through smooth glass (manifold
    /// next-event estimation) and point and spot lights' highlights off glossy surfaces
    /// (light paths).
    pub caustics: Option<bool>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sampler_parses_from_its_name_and_nothing_else_does() {
        for kind in LightSamplerKind::EVERY {
            assert_eq!(kind.name().parse::<LightSamplerKind>(), Ok(kind));
        }
        let e = "bvh".parse::<LightSamplerKind>().unwrap_err();
        assert!(e.contains("'bvh'") && e.contains("uniform, power"), "{e}");
    }

    #[test]
    fn a_clamp_reads_as_blender_writes_it() {
        assert_eq!("10".parse::<Clamp>(), Ok(Clamp { direct: 0.0, indirect: 10.0 }));
        assert_eq!("4, 10".parse::<Clamp>(), Ok(Clamp { direct: 4.0, indirect: 10.0 }));
        assert_eq!("off".parse::<Clamp>(), Ok(Clamp::OFF));
        assert_eq!(Clamp { direct: 4.0, indirect: 10.0 }.to_string(), "4,10");
        for bad in ["-1", "1,x", "inf", "NaN"] {
            assert!(bad.parse::<Clamp>().is_err(), "{bad}");
        }
    }
}
