//! Shared test machinery: statistics (chi-square with pooling and Šidák correction, z-tests),
//! analytic answers (Lambert's polygon formula) and scene builders.

use myriad::light::LightId;
use myriad::light_sampler::{LightSampler, ShadingContext};
use myriad::material::Material;
use myriad::math::distribution::{RANGE, probability};
use myriad::math::{Mat4, Rgb, UVec2, Vec3A};
use myriad::sampling::fmix64;
use myriad::scene::description::{CameraDesc, CameraPlacement, InstanceDesc, LightDesc, MeshDesc, SceneDescription};
use myriad::scene::{BuildOptions, Scene, build};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Significance level of every statistical test, before correction.
pub const ALPHA: f64 = 0.01;

/// ln Γ(x), Lanczos approximation (g = 7, n = 9), accurate to ~1e-15 for x > 0.
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let s: f64 = C[0] + (1..9).map(|i| C[i] / (x + i as f64)).sum::<f64>();
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

/// Regularised upper incomplete gamma Q(a, x) (series below a+1, continued fraction above).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        let (mut sum, mut term, mut n) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - ln_gamma(a)).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - ln_gamma(a)).exp() * h
    }
}

/// Result of a chi-square goodness-of-fit test (all fields appear in failure messages).
#[derive(Debug)]
#[allow(dead_code)]
pub struct ChiSquare {
    /// The statistic.
    pub chi2: f64,
    /// Degrees of freedom after pooling.
    pub dof: usize,
    /// P-value.
    pub p: f64,
}

/// Pearson's chi-square of `observed` counts against `expected` counts (same total). Intervals
/// expected below 5 are pooled (Mitsuba's `chi2.py`); an observation in an interval with expectation
/// 0 is an immediate failure (returns p = 0).
pub fn chi_square(observed: &[f64], expected: &[f64]) -> ChiSquare {
    let mut idx: Vec<usize> = (0..observed.len()).collect();
    idx.sort_by(|&a, &b| expected[a].partial_cmp(&expected[b]).unwrap());
    let (mut chi2, mut dof) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for &i in &idx {
        if expected[i] == 0.0 {
            if observed[i] > 0.0 {
                return ChiSquare { chi2: f64::INFINITY, dof: 0, p: 0.0 };
            }
            continue;
        }
        if expected[i] < 5.0 || pool_e > 0.0 && pool_e < 5.0 {
            pool_o += observed[i];
            pool_e += expected[i];
            if pool_e >= 5.0 {
                chi2 += (pool_o - pool_e).powi(2) / pool_e;
                dof += 1;
                pool_o = 0.0;
                pool_e = 0.0;
            }
            continue;
        }
        chi2 += (observed[i] - expected[i]).powi(2) / expected[i];
        dof += 1;
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e).powi(2) / pool_e;
        dof += 1;
    }
    let dof = dof.saturating_sub(1).max(1);
    ChiSquare { chi2, dof, p: gamma_q(dof as f64 / 2.0, chi2 / 2.0) }
}

/// Per-test significance with a Šidák correction over `tests` tests.
pub fn sidak(tests: usize) -> f64 {
    1.0 - (1.0 - ALPHA).powf(1.0 / tests as f64)
}

/// Two-sided p-value of a standard-normal z.
pub fn z_p_value(z: f64) -> f64 {
    // P(|Z| > z) = Q(1/2, z²/2).
    gamma_q(0.5, z * z / 2.0)
}

/// Running mean of a scalar estimator.
#[derive(Default, Clone, Copy, Debug)]
pub struct Stats {
    n: f64,
    mean: f64,
}

impl Stats {
    /// Adds a sample.
    pub fn add(&mut self, x: f64) {
        self.n += 1.0;
        let d = x - self.mean;
        self.mean += d / self.n;
    }
    /// Mean.
    pub fn mean(&self) -> f64 {
        self.mean
    }
}

/// Irradiance at `p` (normal `n`) from a uniform Lambertian polygon of radiance `l`, corners
/// counter-clockwise seen from its emitting side: Lambert's formula
/// E = L/2 · Σ Θ_k (n · unit(v_k × v_{k+1})), v_k = q_k − p.
pub fn polygon_irradiance(p: Vec3A, n: Vec3A, corners: &[Vec3A], l: f64) -> f64 {
    let k = corners.len();
    let mut sum = 0.0f64;
    for i in 0..k {
        let a = (corners[i] - p).normalize();
        let b = (corners[(i + 1) % k] - p).normalize();
        let theta = (a.dot(b) as f64).clamp(-1.0, 1.0).acos();
        let c = a.cross(b).normalize();
        sum += theta * c.dot(n) as f64;
    }
    // With corners counter-clockwise seen from the receiver side the sum is negative.
    (0.5 * l * sum).abs()
}

/// A scene and the image size it was built for: what tests render. Derefs to the scene.
pub struct TestScene {
    pub scene: Scene,
    pub resolution: UVec2,
}

impl From<myriad::commands::LoadedScene> for TestScene {
    fn from(l: myriad::commands::LoadedScene) -> Self {
        Self { resolution: l.report.resolution, scene: l.scene }
    }
}

impl std::ops::Deref for TestScene {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        &self.scene
    }
}

/// A scene from parts: the camera looks from `eye` to `target` at `resolution`.
pub fn scene_from(
    materials: Vec<Material>,
    meshes: Vec<(MeshDesc, Mat4)>,
    lights: Vec<LightDesc>,
    eye: Vec3A,
    target: Vec3A,
    resolution: UVec2,
) -> TestScene {
    let mut desc = SceneDescription { source: "<test>".into(), materials, lights, ..Default::default() };
    desc.cameras.push(CameraDesc {
        name: "test".into(),
        placement: CameraPlacement::LookAt {
            eye,
            target,
            up: if (target - eye).normalize().y.abs() > 0.99 { Vec3A::Z } else { Vec3A::Y },
        },
        fov: 0.8,
        fit: Default::default(),
        shift: Default::default(),
        lens: None,
        aspect_ratio: None,
    });
    for (i, (mesh, m)) in meshes.into_iter().enumerate() {
        desc.meshes.push(mesh);
        desc.instances.push(InstanceDesc { mesh: i as u32, transform: m, name: format!("mesh {i}") });
    }
    let (scene, report) =
        build(desc, &BuildOptions { resolution: Some(resolution), camera: None, ..Default::default() })
            .expect("test scene builds");
    TestScene { scene, resolution: report.resolution }
}

/// A quad light from corner and edges.
pub fn quad_light(corner: Vec3A, e1: Vec3A, e2: Vec3A, radiance: Rgb, two_sided: bool) -> LightDesc {
    LightDesc::Quad { name: Arc::from("test quad"), corner, edge1: e1, edge2: e2, radiance, two_sided }
}

/// Draw `k` of the independent uniform 64-bit stream `salt` (SplitMix64's output mix).
pub fn draw(k: u64, salt: u64) -> u64 {
    fmix64(fmix64(salt ^ 0x5851_f42d_4c95_7f2d) ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// The lights' intervals at `ctx` tile the 2⁶⁴ values (apart from values that pick nothing, where
/// `sample` must say `None`), every non-empty interval picks its light at both ends and reports its
/// width as the pmf, and the pmfs sum to the share of values that pick something. Exact: no
/// statistics.
pub fn check_intervals_at(sampler: &impl LightSampler, ctx: &ShadingContext, n: usize) {
    let mut intervals: Vec<(u128, u128, u32)> = (0..n as u32)
        .map(|i| {
            let (a, b) = sampler.interval(ctx, LightId(i));
            assert!(a <= b && b <= RANGE, "light {i}: interval {a}..{b}");
            assert_eq!(sampler.pmf(ctx, LightId(i)), probability(b - a), "light {i}");
            (a, b, i)
        })
        .filter(|c| c.1 > c.0)
        .collect();
    intervals.sort();
    let mut covered = 0u128;
    let mut end = 0u128;
    for &(a, b, i) in &intervals {
        assert!(a >= end, "intervals overlap at light {i}");
        if a > end {
            // A gap: values that pick no light.
            assert_eq!(sampler.sample(ctx, end as u64), None, "gap before light {i}");
        }
        for u in [a, b - 1, a + (b - a) / 2] {
            let s = sampler.sample(ctx, u as u64).unwrap_or_else(|| panic!("light {i}'s interval picks nothing"));
            assert_eq!((s.light.0, s.pmf), (i, probability(b - a)), "value {u} in light {i}'s interval");
        }
        covered += b - a;
        end = b;
    }
    if end < RANGE {
        assert_eq!(sampler.sample(ctx, u64::MAX), None, "values past the last interval");
    }
    let total: f64 = (0..n as u32).map(|i| sampler.pmf(ctx, LightId(i)) as f64).sum();
    assert!((total - covered as f64 / RANGE as f64).abs() < 1e-5, "Σ pmf {total}, intervals cover {covered}");
}

/// Pick counts of `draws` independent numbers at `ctx` (drawn on every core) against the
/// pmf, intervals pooled to at least 5 expected picks, with one interval for `None`: a chi-square
/// test. Also checks that no pick has pmf 0.
pub fn pick_chi_square(
    sampler: &impl LightSampler,
    ctx: &ShadingContext,
    n: usize,
    draws: u64,
    salt: u64,
) -> ChiSquare {
    use rayon::prelude::*;
    let pmfs: Vec<f64> = (0..n as u32).into_par_iter().map(|i| sampler.pmf(ctx, LightId(i)) as f64).collect();
    let counts = (0..draws)
        .into_par_iter()
        .fold(
            || vec![0u32; n + 1],
            |mut c, k| {
                match sampler.sample(ctx, draw(k, salt)) {
                    Some(s) => {
                        assert!(s.pmf > 0.0, "sampled light {} with pmf 0", s.light.0);
                        c[s.light.0 as usize] += 1;
                    }
                    None => c[n] += 1,
                }
                c
            },
        )
        .reduce(|| vec![0u32; n + 1], |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect());
    let counts: Vec<f64> = counts.into_iter().map(f64::from).collect();
    let mut expected: Vec<f64> = pmfs.iter().map(|p| p * draws as f64).collect();
    expected.push((1.0 - pmfs.iter().sum::<f64>()).max(0.0) * draws as f64);
    chi_square(&counts, &expected)
}

/// A Blender export in `tests/data/blender/` (its README says what each holds).
pub fn blender(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender").join(name)
}

/// One scene of `tests/data/gltf-variants/` (tools/make_gltf_variants.py), by name.
pub fn gltf_variant(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf-variants").join(format!("{name}.glb"))
}

/// A GLB's JSON chunk and the rest.
pub fn split_glb(bytes: &[u8]) -> Option<(Value, Vec<u8>)> {
    let len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
    let json = serde_json::from_slice(bytes.get(20..20 + len)?).ok()?;
    Some((json, bytes.get(20 + len..)?.to_vec()))
}

/// A GLB from a JSON chunk and the chunks after it, with consistent lengths.
pub fn join_glb(json: &Value, rest: &[u8]) -> Vec<u8> {
    let mut text = json.to_string().into_bytes();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + rest.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend(rest);
    out
}

/// One of the Cornell boxes in `tests/data/cornell/`, by extension.
pub fn cornell(ext: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cornell/cornell").with_extension(ext)
}

/// Loads and builds a scene file as `myriad render` does.
pub fn load(path: &Path, resolution: Option<UVec2>, camera: Option<&str>) -> myriad::Result<TestScene> {
    load_report(path, resolution, camera).map(TestScene::from)
}

/// Loads a scene file as the binary does: the scene with its build report.
pub fn load_report(
    path: &Path,
    resolution: Option<UVec2>,
    camera: Option<&str>,
) -> myriad::Result<myriad::commands::LoadedScene> {
    let options = myriad::commands::SceneOptions {
        load: Default::default(),
        build: BuildOptions { resolution, camera: camera.map(String::from), ..Default::default() },
    };
    myriad::commands::load_scene(Some(path), &options)
}

/// The Cornell glTF as JSON, for tests to break.
pub fn cornell_json() -> Value {
    serde_json::from_str(&std::fs::read_to_string(cornell("gltf")).unwrap()).unwrap()
}

/// Writes `bytes` as `name` in `dir` and loads it, expecting an error: its message.
pub fn load_error(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    match load(&path, Some(UVec2::new(8, 6)), None) {
        Ok(_) => panic!("{name} loaded"),
        Err(e) => e.to_string(),
    }
}

/// Fails unless `message` contains every one of `parts`.
pub fn assert_mentions(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "'{message}' does not mention '{p}'");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_q_matches_known_chi_square_quantiles() {
        // P(χ²_1 > 3.841) = 0.05, P(χ²_10 > 23.209) = 0.01, P(χ²_100 > 124.342) = 0.05.
        assert!((gamma_q(0.5, 3.841 / 2.0) - 0.05).abs() < 1e-3);
        assert!((gamma_q(5.0, 23.209 / 2.0) - 0.01).abs() < 1e-4);
        assert!((gamma_q(50.0, 124.342 / 2.0) - 0.05).abs() < 1e-3);
        assert!((z_p_value(1.96) - 0.05).abs() < 1e-3);
    }

    #[test]
    fn chi_square_accepts_a_fair_die_and_rejects_a_loaded_one() {
        let fair = chi_square(&[101.0, 95.0, 104.0, 99.0, 97.0, 104.0], &[100.0; 6]);
        assert!(fair.p > 0.5, "{fair:?}");
        let loaded = chi_square(&[150.0, 70.0, 100.0, 80.0, 100.0, 100.0], &[100.0; 6]);
        assert!(loaded.p < 1e-6, "{loaded:?}");
        assert_eq!(chi_square(&[1.0, 9.0], &[0.0, 10.0]).p, 0.0);
    }

    #[test]
    fn polygon_formula_matches_a_disk_like_square_on_axis() {
        // Under a small square of area A at height h, E ≈ L·A/h².
        let h = 10.0;
        let s = 0.1;
        let c = [
            Vec3A::new(-s / 2.0, h, -s / 2.0),
            Vec3A::new(s / 2.0, h, -s / 2.0),
            Vec3A::new(s / 2.0, h, s / 2.0),
            Vec3A::new(-s / 2.0, h, s / 2.0),
        ];
        let e = polygon_irradiance(Vec3A::ZERO, Vec3A::Y, &c, 1.0);
        assert!((e / (s as f64 * s as f64 / (h as f64 * h as f64)) - 1.0).abs() < 1e-3, "{e}");
        // A huge square fills the hemisphere: E → π·L.
        let big = c.map(|v| Vec3A::new(v.x * 1e5, 1.0, v.z * 1e5));
        assert!((polygon_irradiance(Vec3A::ZERO, Vec3A::Y, &big, 1.0) - std::f64::consts::PI).abs() < 1e-3);
    }
}
