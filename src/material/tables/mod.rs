//! Tables of GGX integrals that Cycles' Principled BSDF relies on, as myriad computes them:
//! the directional albedo E(r, μ) of a white GGX lobe and its cosine-weighted average Ē(r),
//! for multiple-scattering energy compensation (Kulla & Conty 2017); the same for a rough
//! glass interface (reflection and refraction together, from outside, η > 1, and from inside,
//! 1/η) over r, μ and z; and the average Fresnel weight s(r, μ, z) of a dielectric, for the
//! albedo a specular layer takes from what lies under it.
//!
//! Cycles' sheen lobe is not an integral of ours: `sheen.rs` holds it as measured on Cycles
//! (`tools/measure_sheen.py`), read by [`sheen`].
//!
//! Owns: the integrands ([`ggx_albedo`], [`ggx_albedo_average`], [`fresnel_weight_average`]),
//! the grids (Cycles' layout: node i of n at i/(n−1), roughness fastest, the lowest node moved
//! to 1e-4 and z's highest to 0.99) and multilinear lookups. The numbers live in `data.rs`,
//! written by `cargo run --release --example ggx_tables` (a stratified 2D quadrature of the
//! visible-normal distribution per node, 512² points, 256² for s); a test recomputes some
//! nodes and compares.

mod data;
mod sheen;

use rayon::prelude::*;

use super::fresnel;
use super::microfacet::Ggx;
use crate::math::{Vec2, Vec3A, node_position};

/// Nodes per axis of the E table (roughness × cos θo).
pub const E_NODES: usize = 32;
/// Nodes per axis of the s table (roughness × cos θo × z).
pub const S_NODES: usize = 16;

/// Node `i` of `n` on [0, 1], moved into [lo, hi].
fn node(i: usize, n: usize, lo: f32, hi: f32) -> f32 {
    (i as f32 / (n - 1) as f32).clamp(lo, hi)
}

/// The outgoing direction at cos θo = `mu`.
fn outgoing(mu: f32) -> Vec3A {
    Vec3A::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// The mean of `f(ggx, wo, h)` over `n × n` stratified visible normals `h` of roughness
/// `rough` seen from cos θo = `mu`.
fn over_visible_normals(rough: f32, mu: f32, n: usize, f: impl Fn(&Ggx, Vec3A, Vec3A) -> f64) -> f64 {
    let ggx = Ggx::from_roughness(rough);
    let wo = outgoing(mu);
    let mut sum = 0.0;
    for a in 0..n {
        for b in 0..n {
            let u = Vec2::new((a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32);
            sum += f(&ggx, wo, ggx.sample_visible_normal(wo, u));
        }
    }
    sum / (n * n) as f64
}

/// The mean of `f(wo, h, wi)` over reflections of `wo` about stratified visible normals
/// ([`over_visible_normals`]), 0 for those below the horizon.
fn visible_normal_mean(rough: f32, mu: f32, n: usize, f: impl Fn(&Ggx, Vec3A, Vec3A, Vec3A) -> f64) -> f64 {
    over_visible_normals(rough, mu, n, |ggx, wo, h| {
        let wi = 2.0 * wo.dot(h) * h - wo;
        if wi.z > 0.0 { f(ggx, wo, h, wi) } else { 0.0 }
    })
}

/// Directional albedo of a white GGX reflection lobe, ∫ D·G2/(4μo) dωi = E_vndf[G2/G1].
pub fn ggx_albedo(rough: f32, mu: f32, n: usize) -> f64 {
    visible_normal_mean(rough, mu, n, |g, wo, _, wi| (g.g2(wo, wi) / g.g1(wo)) as f64)
}

/// ∫₀¹ 2μ·E(r, μ) dμ by the midpoint rule over `steps` cosines.
pub fn ggx_albedo_average(rough: f32, steps: usize, n: usize) -> f64 {
    (0..steps)
        .map(|k| {
            let mu = (k as f32 + 0.5) / steps as f32;
            2.0 * mu as f64 * ggx_albedo(rough, mu, n) / steps as f64
        })
        .sum()
}

/// Albedo of a white rough glass interface seen from `wo` at cos θo = `mu`, relative IOR
/// `eta` (the far side over `wo`'s side): each visible normal reflects with the exact Fresnel
/// F and refracts with 1 − F (total internal reflection reflects all), and each direction
/// that stays on its side counts G2/G1, without the η² of radiance compression (Cycles').
pub fn ggx_glass_albedo(rough: f32, mu: f32, eta: f32, n: usize) -> f64 {
    over_visible_normals(rough, mu, n, |ggx, wo, h| {
        let cos = wo.dot(h);
        let f = fresnel::dielectric(cos, eta);
        let reflected = 2.0 * cos * h - wo;
        let mut sum = 0.0;
        if reflected.z > 0.0 {
            sum += f as f64 * (ggx.g2(wo, reflected) / ggx.g1(wo)) as f64;
        }
        if let Some(refracted) = super::microfacet::refract(wo, h, eta)
            && refracted.z < 0.0
        {
            sum += (1.0 - f) as f64 * (ggx.g2(wo, -refracted) / ggx.g1(wo)) as f64;
        }
        sum
    })
}

/// ∫₀¹ 2μ·E_glass(r, μ, η) dμ by the midpoint rule over `steps` cosines.
pub fn ggx_glass_albedo_average(rough: f32, eta: f32, steps: usize, n: usize) -> f64 {
    (0..steps)
        .map(|k| {
            let mu = (k as f32 + 0.5) / steps as f32;
            2.0 * mu as f64 * ggx_glass_albedo(rough, mu, eta, n) / steps as f64
        })
        .sum()
}

/// The IOR at z = F0(η)^¼, the s table's third axis.
pub fn ior_of_z(z: f32) -> f32 {
    fresnel::ior_from_f0(z.powi(4))
}

/// The average over visible normals of how far the exact dielectric Fresnel has gone from
/// F0 to 1: saturate((F(wo·h, η) − F0(η)) / (1 − F0(η))), η = [`ior_of_z`]`(z)`.
pub fn fresnel_weight_average(rough: f32, mu: f32, z: f32, n: usize) -> f64 {
    let eta = ior_of_z(z);
    let f0 = fresnel::f0_from_ior(eta);
    visible_normal_mean(rough, mu, n, |_, wo, h, _| {
        ((fresnel::dielectric(wo.dot(h), eta) - f0) / (1.0 - f0)).clamp(0.0, 1.0) as f64
    })
}

/// The glass tables, computed: E and Ē from outside (η = [`ior_of_z`]) and from inside (1/η).
pub fn compute_glass(n: usize) -> [Vec<f32>; 4] {
    let cells = |inside: bool| -> Vec<f32> {
        (0..S_NODES * S_NODES * S_NODES)
            .into_par_iter()
            .map(|k| {
                let r = node(k % S_NODES, S_NODES, 1e-4, 1.0);
                let m = node(k / S_NODES % S_NODES, S_NODES, 1e-4, 1.0);
                let eta = ior_of_z(node(k / (S_NODES * S_NODES), S_NODES, 1e-4, 0.99));
                ggx_glass_albedo(r, m, if inside { 1.0 / eta } else { eta }, n) as f32
            })
            .collect()
    };
    let averages = |inside: bool| -> Vec<f32> {
        (0..S_NODES * S_NODES)
            .into_par_iter()
            .map(|k| {
                let r = node(k % S_NODES, S_NODES, 1e-4, 1.0);
                let eta = ior_of_z(node(k / S_NODES, S_NODES, 1e-4, 0.99));
                ggx_glass_albedo_average(r, if inside { 1.0 / eta } else { eta }, 32, n / 2) as f32
            })
            .collect()
    };
    [cells(false), averages(false), cells(true), averages(true)]
}

/// The tables, computed (what the generator writes): E, Ē and s.
pub fn compute(n: usize) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let e: Vec<f32> = (0..E_NODES * E_NODES)
        .into_par_iter()
        .map(|k| {
            let (r, m) = (node(k % E_NODES, E_NODES, 1e-4, 1.0), node(k / E_NODES, E_NODES, 1e-4, 1.0));
            ggx_albedo(r, m, n) as f32
        })
        .collect();
    let e_avg: Vec<f32> =
        (0..E_NODES).into_par_iter().map(|k| ggx_albedo_average(node(k, E_NODES, 1e-4, 1.0), 64, n) as f32).collect();
    let s: Vec<f32> = (0..S_NODES * S_NODES * S_NODES)
        .into_par_iter()
        .map(|k| {
            let r = node(k % S_NODES, S_NODES, 1e-4, 1.0);
            let m = node(k / S_NODES % S_NODES, S_NODES, 1e-4, 1.0);
            let z = node(k / (S_NODES * S_NODES), S_NODES, 1e-4, 0.99);
            fresnel_weight_average(r, m, z, n / 2) as f32
        })
        .collect();
    (e, e_avg, s)
}

/// Bilinear lookup in a table of `N × N` (x fastest).
#[inline]
fn lookup2<const N: usize>(table: &[f32], x: f32, y: f32) -> f32 {
    bilinear::<N>(table, node_position::<N>(x), node_position::<N>(y))
}

/// The bilinear interpolation at a cell's corner (i, j) and fractions (fx, fy).
#[inline(always)]
fn bilinear<const N: usize>(table: &[f32], (i, fx): (usize, f32), (j, fy): (usize, f32)) -> f32 {
    // One bounds check for the cell's four corners.
    let cell = &table[j * N + i..][..N + 2];
    let lo = cell[0] + (cell[1] - cell[0]) * fx;
    let hi = cell[N] + (cell[N + 1] - cell[N]) * fx;
    lo + (hi - lo) * fy
}

/// Directional albedo E(r, μ) of a white GGX lobe of perceptual roughness `rough`.
#[inline]
pub fn albedo(rough: f32, mu: f32) -> f32 {
    lookup2::<E_NODES>(&data::GGX_E, rough, mu)
}

/// Ē(r), the cosine-weighted average of [`albedo`].
#[inline]
pub fn albedo_average(rough: f32) -> f32 {
    let (i, f) = node_position::<E_NODES>(rough);
    data::GGX_E_AVG[i] + (data::GGX_E_AVG[i + 1] - data::GGX_E_AVG[i]) * f
}

/// Cycles' sheen lobe at perceptual `rough`ness and cos θo = `mu` (bilinear in the measured
/// table, `sheen.rs`): the linearly transformed cosine's a and b, and the lobe's albedo.
#[inline]
pub fn sheen(rough: f32, mu: f32) -> [f32; 3] {
    const N: usize = sheen::NODES;
    let ((i, fx), (j, fy)) = (node_position::<N>(mu), node_position::<N>(rough));
    let at = |a: usize, b: usize| Vec3A::from(sheen::SHEEN[b * N + a]);
    let lo = at(i, j).lerp(at(i + 1, j), fx);
    let hi = at(i, j + 1).lerp(at(i + 1, j + 1), fx);
    lo.lerp(hi, fy).to_array()
}

/// Trilinear lookup in a table of `N³` (x fastest).
#[inline]
fn lookup3<const N: usize>(table: &[f32], x: f32, y: f32, z: f32) -> f32 {
    let (at_x, at_y, (k, fz)) = (node_position::<N>(x), node_position::<N>(y), node_position::<N>(z));
    let plane = |k: usize| bilinear::<N>(&table[k * N * N..], at_x, at_y);
    let (a, b) = (plane(k), plane(k + 1));
    a + (b - a) * fz
}

/// s(r, μ, z): the average Fresnel weight of a dielectric lobe (z = F0(η)^¼).
#[inline]
pub fn fresnel_weight(rough: f32, mu: f32, z: f32) -> f32 {
    lookup3::<S_NODES>(&data::GGX_GEN_SCHLICK_IOR_S, rough, mu, z)
}

/// The glass tables' z axis for relative IOR `eta` (on either side), and whether it is the
/// inside table.
#[inline]
fn glass_axis(eta: f32) -> (f32, bool) {
    let outside = eta >= 1.0;
    (fresnel::f0_from_ior(if outside { eta } else { 1.0 / eta }).sqrt().sqrt(), !outside)
}

/// Albedo of a white rough glass interface of relative IOR `eta` at cos θo = `mu`.
#[inline]
pub fn glass_albedo(rough: f32, mu: f32, eta: f32) -> f32 {
    let (z, inside) = glass_axis(eta);
    lookup3::<S_NODES>(if inside { &data::GGX_GLASS_INV_E } else { &data::GGX_GLASS_E }, rough, mu, z)
}

/// Its cosine-weighted average over the hemisphere.
#[inline]
pub fn glass_albedo_average(rough: f32, eta: f32) -> f32 {
    let (z, inside) = glass_axis(eta);
    lookup2::<S_NODES>(if inside { &data::GGX_GLASS_INV_E_AVG } else { &data::GGX_GLASS_E_AVG }, rough, z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_hold_what_their_integrands_give() {
        // A few nodes recomputed with fewer samples than the generator used.
        for (ri, mi) in [(0, 31), (5, 3), (16, 16), (31, 1), (31, 31), (10, 25)] {
            let (r, m) = (node(ri, E_NODES, 1e-4, 1.0), node(mi, E_NODES, 1e-4, 1.0));
            let stored = data::GGX_E[mi * E_NODES + ri];
            assert!((ggx_albedo(r, m, 128) as f32 - stored).abs() < 2e-3, "E({r}, {m}) = {stored}");
        }
        for ri in [0, 7, 20, 31] {
            let r = node(ri, E_NODES, 1e-4, 1.0);
            // The grid's error near grazing angles is a few 1e-3 at 128² (1e-3 at 512²).
            let recomputed = ggx_albedo_average(r, 64, 128) as f32;
            assert!(
                (recomputed - data::GGX_E_AVG[ri]).abs() < 5e-3,
                "Ē({r}) = {} vs {recomputed}",
                data::GGX_E_AVG[ri]
            );
        }
        for (ri, mi, zi) in [(0, 15, 3), (8, 4, 8), (15, 15, 15), (3, 1, 0)] {
            let (r, m, z) = (node(ri, S_NODES, 1e-4, 1.0), node(mi, S_NODES, 1e-4, 1.0), node(zi, S_NODES, 1e-4, 0.99));
            let stored = data::GGX_GEN_SCHLICK_IOR_S[(zi * S_NODES + mi) * S_NODES + ri];
            assert!((fresnel_weight_average(r, m, z, 96) as f32 - stored).abs() < 3e-3, "s({r}, {m}, {z}) = {stored}");
        }
    }

    #[test]
    fn the_glass_tables_hold_what_their_integrand_gives() {
        for (ri, mi, zi) in [(0, 15, 3), (8, 4, 8), (15, 15, 15), (5, 1, 10)] {
            let (r, m, z) = (node(ri, S_NODES, 1e-4, 1.0), node(mi, S_NODES, 1e-4, 1.0), node(zi, S_NODES, 1e-4, 0.99));
            let k = (zi * S_NODES + mi) * S_NODES + ri;
            for (eta, stored) in [(ior_of_z(z), data::GGX_GLASS_E[k]), (1.0 / ior_of_z(z), data::GGX_GLASS_INV_E[k])] {
                assert!(
                    (ggx_glass_albedo(r, m, eta, 96) as f32 - stored).abs() < 3e-3,
                    "E_glass({r}, {m}, {eta}) = {stored}"
                );
            }
        }
        // A smooth interface keeps everything (reflection plus refraction).
        assert!(glass_albedo(0.0, 0.7, 1.5) > 0.99 && glass_albedo(0.0, 0.7, 1.0 / 1.5) > 0.99);
        assert!(glass_albedo(1.0, 0.7, 1.5) < 0.9);
    }

    #[test]
    fn a_white_lobe_keeps_what_a_brute_force_integral_gives() {
        // ∫ D·G2/(4μo) dωi by a 200 × 400 midpoint sum over the hemisphere of ωi (done once,
        // outside): a mirror keeps everything; roughness 1 loses most at normal incidence.
        assert!(albedo(0.0, 1.0) > 0.99 && albedo(0.0, 0.5) > 0.99);
        assert!((albedo(1.0, 1.0) - 0.3069).abs() < 2e-3, "{}", albedo(1.0, 1.0));
        assert!((albedo(1.0, 0.5) - 0.4507).abs() < 5e-3, "{}", albedo(1.0, 0.5));
        assert!((albedo(0.5, 0.5) - 0.8573).abs() < 5e-3, "{}", albedo(0.5, 0.5));
        assert!(albedo_average(1.0) < albedo_average(0.5) && albedo_average(0.0) > 0.99);
        // The Fresnel weight rises towards grazing and with roughness at normal incidence.
        assert!(fresnel_weight(0.0, 1.0, 0.45) < 1e-3 && fresnel_weight(0.0, 0.05, 0.45) > 0.4);
    }
}
