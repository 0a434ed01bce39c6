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
    /// choice; for 8 to 1024 lights, the tree outside that range and in cells next to lights).
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
}
