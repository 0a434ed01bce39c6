//! Lamps as Cycles renders Blender's lights: point and spot lamps with a radius (a facing
//! disk or a sphere), rectangle and ellipse area lamps with a spread, suns with an angle.
//! Each renders a Lambertian floor to the irradiance a quadrature of the lamp's own shape
//! gives (so next-event estimation and BSDF rays that meet the lamp, weighted by MIS, add up
//! to the integral), lamps between a light and the floor cast no shadow, and the camera sees
//! a lamp only where it is visible, with its radiance.

use std::f32::consts::PI;
use std::sync::Arc;

use crate::common::{TestScene, polygon_irradiance, scene_from, sidak};
use crate::render::{check_against, render_with};
use myriad::light::{LampModel, SpotCurve};
use myriad::material::Material;
use myriad::math::{Mat4, Rgb, UVec2, Vec2, Vec3A};
use myriad::scene::description::{LampShape, LightDesc};
use myriad::scene::shapes::quad_mesh;
use myriad::settings::LightSamplerKind;

/// Points and area weights covering the ellipse `c + x·u + y·v`, x² + y² ≤ 1 (a polar grid
/// of `k × 4k` cells).
fn ellipse_points(c: Vec3A, u: Vec3A, v: Vec3A, k: usize) -> Vec<(Vec3A, f64)> {
    let scale = u.cross(v).length() as f64;
    let mut points = Vec::new();
    for i in 0..k {
        let (r0, r1) = (i as f64 / k as f64, (i + 1) as f64 / k as f64);
        let r = 0.5 * (r0 + r1);
        for j in 0..4 * k {
            let phi = (j as f64 + 0.5) / (4 * k) as f64 * std::f64::consts::TAU;
            let area = 0.5 * (r1 * r1 - r0 * r0) * std::f64::consts::TAU / (4 * k) as f64;
            let (x, y) = ((r * phi.cos()) as f32, (r * phi.sin()) as f32);
            points.push((c + u * x + v * y, area * scale));
        }
    }
    points
}

/// Irradiance at `p` (normal +Y) from radiance `l(q, ω)` over surface points `points` of
/// normal `n(q)` (ω: the unit direction from q to p).
fn integrate(p: Vec3A, points: &[(Vec3A, f64)], n: impl Fn(Vec3A) -> Vec3A, l: impl Fn(Vec3A, Vec3A) -> f64) -> f64 {
    points
        .iter()
        .map(|&(q, da)| {
            let w = p - q;
            let t2 = w.length_squared() as f64;
            let omega = w.normalize();
            let (cos_l, cos_r) = (omega.dot(n(q)) as f64, (-omega).dot(Vec3A::Y) as f64);
            if cos_l <= 0.0 || cos_r <= 0.0 { 0.0 } else { l(q, omega) * cos_l * cos_r / t2 * da }
        })
        .sum()
}

fn lamp(radius: f32, model: LampModel) -> Option<LampShape> {
    Some(LampShape { radius, model, camera_visible: false })
}

/// The floor at y = 0 seen from straight above through `res` pixels.
fn floor_scene(lights: Vec<LightDesc>, res: UVec2) -> TestScene {
    let floor =
        quad_mesh("floor", Vec3A::new(-3.0, 0.0, 3.0), Vec3A::new(6.0, 0.0, 0.0), Vec3A::new(0.0, 0.0, -6.0), 0);
    scene_from(
        vec![Material::diffuse("floor", Rgb::splat(0.5))],
        vec![(floor, Mat4::IDENTITY)],
        lights,
        Vec3A::new(0.0, 3.0, 0.0),
        Vec3A::ZERO,
        res,
    )
}

/// Expected pixel values of the floor under irradiance `e`: ρ/π·E averaged over each pixel's
/// footprint (4 × 4 points).
fn expected_pixels(scene: &TestScene, e: &dyn Fn(Vec3A) -> f64) -> Vec<f64> {
    let res = scene.resolution;
    (0..res.x * res.y)
        .map(|i| {
            let pixel = UVec2::new(i % res.x, i / res.x);
            let mut acc = 0.0;
            for s in 0..16 {
                let j = Vec2::new(((s % 4) as f32 + 0.5) / 4.0, ((s / 4) as f32 + 0.5) / 4.0);
                let ray = scene.camera.ray(pixel, res, j);
                acc += e(ray.at(-ray.origin.y / ray.dir.y));
            }
            acc / 16.0 * 0.5 / std::f64::consts::PI
        })
        .collect()
}

#[test]
fn every_lamp_lights_a_floor_with_the_integral_of_its_shape_and_casts_no_shadow() {
    let name = |s: &str| -> Arc<str> { Arc::from(s) };
    let i = Rgb::splat(2.0);
    let spot = |p: Vec3A| LightDesc::Spot {
        name: name("spot lamp"),
        position: p,
        direction: -Vec3A::Y,
        intensity: i,
        inner_angle: 0.45,
        outer_angle: 0.6,
        curve: SpotCurve::Smoothstep,
        lamp: lamp(0.15, LampModel::FacingDisk),
    };
    let area = |c: Vec3A, u: Vec3A, v: Vec3A, ellipse, spread| LightDesc::Area {
        name: name("area lamp"),
        center: c,
        u,
        v,
        ellipse,
        radiance: Rgb::splat(3.0),
        spread,
        camera_visible: false,
    };
    // Half sides along X and Z: u × v = X × Z = −Y, facing the floor.
    let lights = vec![
        LightDesc::Point {
            name: name("disk lamp"),
            position: Vec3A::new(-1.0, 0.3, -1.0),
            intensity: i,
            lamp: lamp(0.2, LampModel::FacingDisk),
        },
        LightDesc::Point {
            name: name("sphere lamp"),
            position: Vec3A::new(1.0, 0.4, -1.0),
            intensity: i,
            lamp: lamp(0.15, LampModel::Sphere),
        },
        spot(Vec3A::new(0.0, 0.6, 0.0)),
        area(Vec3A::new(-1.0, 0.5, 1.0), Vec3A::X * 0.3, Vec3A::Z * 0.2, false, PI),
        area(Vec3A::new(1.0, 0.5, 1.0), Vec3A::X * 0.3, Vec3A::Z * 0.2, true, 1.2),
        // High above every lamp: they must not shadow it.
        LightDesc::Point {
            name: name("point"),
            position: Vec3A::new(0.0, 2.0, 0.0),
            intensity: Rgb::splat(1.5),
            lamp: None,
        },
    ];
    let scene = floor_scene(lights, UVec2::new(12, 12));
    let disk_e = |p: Vec3A, c: Vec3A, r: f32, att: &dyn Fn(Vec3A) -> f64| {
        let n = (p - c).normalize();
        let frame = myriad::math::frame::Frame::from_normal(n);
        let pts = ellipse_points(c, frame.s * r, frame.t * r, 60);
        let l = 2.0 / (PI * r * r) as f64;
        integrate(p, &pts, |_| n, |_, omega| l * att(omega))
    };
    let e = |p: Vec3A| -> f64 {
        let mut e = disk_e(p, Vec3A::new(-1.0, 0.3, -1.0), 0.2, &|_| 1.0);
        // The sphere's cap is above the floor's horizon everywhere: exactly I·cos/d².
        let d = Vec3A::new(1.0, 0.4, -1.0) - p;
        e += 2.0 * (d.normalize().y / d.length_squared()) as f64;
        let (cos_o, cos_i) = (0.6f32.cos(), 0.45f32.cos());
        let att = |omega: Vec3A| {
            let t = ((omega.dot(-Vec3A::Y) - cos_o) / (cos_i - cos_o)).clamp(0.0, 1.0) as f64;
            t * t * (3.0 - 2.0 * t)
        };
        e += disk_e(p, Vec3A::new(0.0, 0.6, 0.0), 0.15, &att);
        let c = Vec3A::new(-1.0, 0.5, 1.0);
        let corners = [
            c - Vec3A::new(0.3, 0.0, 0.2),
            c + Vec3A::new(0.3, 0.0, -0.2),
            c + Vec3A::new(0.3, 0.0, 0.2),
            c + Vec3A::new(-0.3, 0.0, 0.2),
        ];
        e += polygon_irradiance(p, Vec3A::Y, &corners, 3.0);
        // The spread ellipse: L0·N·max(tan(s/2) − tan θ, 0), N = 1/(tan(s/2) − s/2).
        let pts = ellipse_points(Vec3A::new(1.0, 0.5, 1.0), Vec3A::X * 0.3, Vec3A::Z * 0.2, 60);
        let half = 0.6f64;
        let norm = 1.0 / (half.tan() - half);
        e += integrate(
            p,
            &pts,
            |_| -Vec3A::Y,
            |_, omega| {
                let cos = omega.dot(-Vec3A::Y) as f64;
                let tan = (1.0 - cos * cos).sqrt() / cos;
                3.0 * norm * (half.tan() - tan).max(0.0)
            },
        );
        let d = Vec3A::new(0.0, 2.0, 0.0) - p;
        e + 1.5 * (d.normalize().y / d.length_squared()) as f64
    };
    let expected = expected_pixels(&scene, &e);
    let kinds = [LightSamplerKind::All, LightSamplerKind::Uniform, LightSamplerKind::Tree, LightSamplerKind::Cells];
    for kind in kinds {
        let film = render_with(&scene, kind, 512, 1, 5);
        check_against(&film, &|k| Rgb::splat(expected[k] as f32), sidak(kinds.len()), kind.name());
    }
}

#[test]
fn a_sun_with_an_angle_gives_its_irradiance_and_rays_that_leave_see_its_disk() {
    let dir = Vec3A::new(0.3, -1.0, 0.2).normalize();
    let sun = LightDesc::Directional {
        name: Arc::from("sun"),
        direction: dir,
        irradiance: Rgb::splat(2.0),
        angle: 0.4,
        camera_visible: false,
    };
    let scene = floor_scene(vec![sun], UVec2::new(6, 6));
    // The whole cone (0.2 rad) is above the floor's horizon: E = S·cos θ.
    let expected = 2.0 * 0.5 / PI * (-dir.y);
    for kind in [LightSamplerKind::All, LightSamplerKind::Tree] {
        let film = render_with(&scene, kind, 256, 1, 2);
        check_against(&film, &|_| Rgb::splat(expected), 0.005, kind.name());
    }
}

#[test]
fn the_camera_sees_a_lamp_only_where_it_is_visible_and_with_its_radiance() {
    // Two lamps side by side 2 m above the camera, facing down (u × v = X × Z = −Y), each
    // filling one of the two pixels: the visible one shows L0 = 7, the hidden one the black
    // behind it.
    let area = |visible, x: f32| LightDesc::Area {
        name: Arc::from("area lamp"),
        center: Vec3A::new(x, 1.0, 0.0),
        u: Vec3A::X * 1.0,
        v: Vec3A::Z * 1.0,
        ellipse: false,
        radiance: Rgb::splat(7.0),
        spread: PI,
        camera_visible: visible,
    };
    let scene = scene_from(
        vec![Material::diffuse("unused", Rgb::ONE)],
        vec![],
        vec![area(true, -1.0), area(false, 1.0)],
        Vec3A::new(0.0, -1.0, 0.0),
        Vec3A::new(0.0, 1.0, 0.0),
        UVec2::new(2, 1),
    );
    let film = render_with(&scene, LightSamplerKind::Tree, 4, 1, 1);
    let (a, b) = (film.mean(0), film.mean(1));
    // Which pixel shows which lamp depends on the camera's up vector looking straight up:
    // one must show 7 and the other nothing.
    let (seen, hidden) = if a.x > b.x { (a, b) } else { (b, a) };
    assert!((seen.x - 7.0).abs() < 1e-4 && hidden == Rgb::ZERO, "{a} {b}");
}
