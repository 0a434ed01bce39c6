//! What light selection may know of a BSDF that is not Lambert's: where it reflects most.
//!
//! Owns: [`GlossyLobes`] and its weights towards clusters, [`GlossyLobes::weights`]. A light tree
//! that weighs clusters only by the irradiance they can bring (Conty Estevez & Kulla) gives a
//! point light mirrored by a glossy floor the probability of any light as far away, and the
//! rare sample that chooses it carries the lobe's peak divided by that probability: the
//! glossy-floor fireflies of `lobby.glb`. Weighing each cluster also by the BSDF towards it,
//! as Tokuyoshi et al. 2023 (hierarchical light sampling with accurate spherical Gaussian
//! lighting) do with their lobe approximation, moves those samples where the BSDF sends
//! them. Any positive weight keeps the estimate unbiased (the pmf is computed as realised);
//! a closer one only lowers its variance.

use crate::math::Vec3A;
use std::f32::consts::FRAC_1_PI;
use wide::f32x8;

/// The narrowest GGX width α selection weighs by: a near-mirror's lobe is weighed as one of
/// roughness 0.14, so that clusters whose bounding spheres only graze the mirror direction
/// are not given everything.
pub const MIN_SELECTION_ALPHA: f32 = 0.02;

/// A BSDF as light selection weighs it: its reflected energy split between a diffuse part
/// and up to two isotropic GGX lobes about the mirror direction of the outgoing one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlossyLobes {
    /// The mirror direction of the outgoing direction about the shading normal (world, unit).
    pub mirror: Vec3A,
    /// Share of the reflected energy that is diffuse (Lambert's lobe, the sheen).
    pub diffuse: f32,
    /// Each glossy lobe's share and squared GGX width α² (α at least
    /// `MIN_SELECTION_ALPHA`, 0.02; a share of 0 for an absent lobe).
    pub glossy: [(f32, f32); 2],
}

impl GlossyLobes {
    /// The lobes for a BSDF whose energy is `diffuse` and `glossy` (share, GGX α) about
    /// `mirror`.
    pub fn new(mirror: Vec3A, diffuse: f32, glossy: [(f32, f32); 2]) -> Self {
        let glossy = glossy.map(|(share, alpha)| (share, alpha.max(MIN_SELECTION_ALPHA).powi(2)));
        Self { mirror, diffuse, glossy }
    }

    /// The BSDF's mean weight (per steradian, without the cosine) over lights that subtend
    /// `solid_angle` at angles θ from the mirror direction, given cos θ per lane: the diffuse
    /// share over π plus, for each lobe, its share times its GGX density at the half-angle
    /// θ/2 over 4 (the mirror mapping's Jacobian at normal incidence), but at most its share
    /// over the solid angle (a cluster wider than the lobe gets the lobe's energy, not its
    /// peak over all of it). Positive everywhere, largest at the mirror direction; eight
    /// clusters at once, as a light tree weighs a node's children.
    #[inline(always)]
    pub fn weights(&self, cos_theta: f32x8, solid_angle: f32x8) -> f32x8 {
        // cos² of the half angle; the GGX density α² / (π (cos²θh (α² − 1) + 1)²).
        let half = (cos_theta + 1.0) * 0.5;
        // A light of no extent (a point, a delta sun) leaves the density uncapped.
        let solid_angle = solid_angle.fast_max(f32x8::splat(1e-30));
        let lobe = |(share, a2): (f32, f32)| {
            let den = half * (a2 - 1.0) + 1.0;
            (f32x8::splat(share * a2 * 0.25 * FRAC_1_PI) / (den * den)).fast_min(share / solid_angle)
        };
        lobe(self.glossy[0]) + lobe(self.glossy[1]) + self.diffuse * FRAC_1_PI
    }

    /// [`weights`](Self::weights) for one direction to a light of no extent.
    #[cfg(test)]
    pub(crate) fn weight(&self, cos_theta: f32) -> f32 {
        self.weights(f32x8::splat(cos_theta), f32x8::ZERO).as_array_ref()[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_weight_peaks_at_the_mirror_direction_and_stays_positive() {
        let lobes = GlossyLobes::new(Vec3A::Z, 0.2, [(0.8, 0.1), (0.0, 1.0)]);
        let at = |deg: f32| lobes.weight(deg.to_radians().cos());
        let mut last = f32::INFINITY;
        for deg in [0.0, 5.0, 20.0, 60.0, 120.0, 180.0] {
            let w = at(deg);
            assert!(w > 0.0 && w <= last, "{deg}°: {w}");
            last = w;
        }
        // At the mirror direction the lobe's GGX peak: 1 / (π α²), times its share over 4.
        let peak = 0.2 / std::f32::consts::PI + 0.8 * 0.25 / (std::f32::consts::PI * 0.01);
        assert!((at(0.0) / peak - 1.0).abs() < 1e-5, "{} vs {peak}", at(0.0));
        // A diffuse BSDF weighs every direction alike.
        let flat = GlossyLobes::new(Vec3A::Z, 1.0, [(0.0, 0.5); 2]);
        assert!((flat.weight(1.0) - flat.weight(-1.0)).abs() < 1e-7);
    }

    #[test]
    fn each_lobe_integrates_to_its_share_at_normal_incidence() {
        // ∫ weight · cos θi dω over the hemisphere about the normal, mirror = normal: the
        // GGX lobes' half-angle map makes each integrate to about its share (exactly only
        // for narrow lobes, where cos θi ≈ 1 over the lobe).
        for alpha in [0.05f32, 0.1] {
            let lobes = GlossyLobes::new(Vec3A::Z, 0.0, [(1.0, alpha), (0.0, 1.0)]);
            let n = 20_000;
            let sum: f64 = (0..n)
                .map(|k| {
                    let theta = (k as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
                    let w = lobes.weight(theta.cos() as f32) as f64;
                    w * theta.cos() * theta.sin() * 2.0 * std::f64::consts::PI * std::f64::consts::FRAC_PI_2 / n as f64
                })
                .sum();
            assert!((sum - 1.0).abs() < 0.1, "α {alpha}: {sum}");
        }
    }
}
