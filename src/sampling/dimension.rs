//! Named random dimensions: which number of a bounce is used for what.
//!
//! Cycles keeps a fixed table of per-bounce dimensions (`PRNG_*`); so do we. Because every
//! number is addressed by name, a sampler that consumes nothing (`all`) or remaps its number
//! (`tree`) never shifts the numbers other decisions see, and two samplers compared at equal
//! spp see the same camera rays and BSDF directions.

/// A named random dimension within one bounce. Each is one seed of the scrambled Sobol
/// sequence, 1D or 2D alike (a 2D dimension takes both coordinates of one point); the gaps
/// between the values are historical and keep images bit-identical to earlier versions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Dim {
    /// Sub-pixel position of the camera ray (2D; bounce 0 only).
    PixelJitter = 0,
    /// The one number a light sampler gets to choose a light.
    LightSelect = 2,
    /// Point on the chosen light (2D).
    LightPoint = 3,
    /// Choice of BSDF lobe.
    BsdfLobe = 5,
    /// Direction within the lobe (2D).
    BsdfDirection = 6,
    /// Russian-roulette survival test.
    RussianRoulette = 8,
    /// Point on the camera's lens aperture (2D; bounce 0 only, with depth of field).
    Lens = 9,
    /// Whether path guiding or the BSDF draws the direction.
    GuideChoice = 10,
    /// Direction drawn from the guide's distribution (2D).
    GuideDirection = 11,
    /// The light a camera sample's light path starts from (bounce 0 only).
    LightPathLight = 12,
    /// The direction it leaves that light in (2D; bounce 0 only).
    LightPathDirection = 13,
}

impl Dim {
    /// Slots one bounce spans; a multiple of the largest dimension index + 2.
    pub const SLOTS: u64 = 16;
}
