//! Procedural shapes: quads, boxes, icospheres and light grids as description data.
//!
//! Owns: turning a few parameters into [`MeshDesc`]s and [`LightDesc`]s. File-free, so the RON
//! loader, tests and benches share it.

use std::collections::HashMap;
use std::sync::Arc;

use super::description::{LightDesc, MeshDesc};
use super::format::{GridEmission, GridSpec};
use crate::limits::{BYTES_PER_LIGHT, BYTES_PER_TRIANGLE, check_memory};
use crate::math::{Rgb, Vec3A, luminance};
use crate::sampling::fmix64;

/// A parallelogram as a two-triangle mesh (emissive, it becomes one quad light).
pub fn quad_mesh(name: &str, corner: Vec3A, edge1: Vec3A, edge2: Vec3A, material: u32) -> MeshDesc {
    MeshDesc {
        name: name.to_string(),
        positions: vec![corner, corner + edge1, corner + edge1 + edge2, corner + edge2],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        material,
        ..Default::default()
    }
}

/// An axis-aligned box of edge lengths `size` centred at the origin, faces pointing out.
pub fn box_mesh(name: &str, size: Vec3A, material: u32) -> MeshDesc {
    let h = size * 0.5;
    let mut mesh = MeshDesc { name: name.to_string(), material, ..Default::default() };
    // For each axis and sign: the face's centre offset and two edges whose cross is outward.
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3A::from(glam::Vec3::AXES[axis]) * sign;
            let u = Vec3A::from(glam::Vec3::AXES[(axis + 1) % 3]);
            let v = Vec3A::from(glam::Vec3::AXES[(axis + 2) % 3]);
            let (e1, e2) = if sign > 0.0 { (u, v) } else { (v, u) };
            let (e1, e2) = (e1 * h * 2.0, e2 * h * 2.0);
            let corner = n * h - 0.5 * (e1 + e2);
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([corner, corner + e1, corner + e1 + e2, corner + e2]);
            mesh.triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
    }
    mesh
}

/// A sphere as a subdivided icosahedron with smooth normals.
pub fn sphere_mesh(name: &str, center: Vec3A, radius: f32, subdivisions: u32, material: u32) -> MeshDesc {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3A> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3A::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, verts: &mut Vec<Vec3A>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((verts[a as usize] + verts[b as usize]).normalize());
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let (ab, bc, ca) = (mid(a, b, &mut verts), mid(b, c, &mut verts), mid(c, a, &mut verts));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    MeshDesc {
        name: name.to_string(),
        positions: verts.iter().map(|&v| center + v * radius).collect(),
        normals: Some(verts),
        uvs: None,
        triangles: tris,
        material,
    }
}

/// Uniform number in [0,1) for (seed, lamp, channel), for the grid's variations.
fn grid_random(seed: u64, lamp: u64, channel: u64) -> f32 {
    let h = fmix64(fmix64(seed ^ 0x6a09_e667_f3bc_c908) ^ lamp.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (channel << 56));
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// The lamps of a grid, or a message saying which parameter is unusable.
pub fn light_grid(name: &str, g: &GridSpec) -> Result<Vec<LightDesc>, String> {
    let n = Vec3A::from(g.normal).try_normalize().ok_or("`normal` must be a non-zero vector")?;
    let hint = match g.tangent {
        Some(t) => Vec3A::from(t),
        None if n.x.abs() > 0.9 => Vec3A::Z,
        None => Vec3A::X,
    };
    let tangent = (hint - n * hint.dot(n)).try_normalize().ok_or("`tangent` must not be parallel to `normal`")?;
    let bitangent = n.cross(tangent);
    if g.rows == 0 || g.cols == 0 {
        return Err("`rows` and `cols` must be at least 1".into());
    }
    if !(g.extent.0 > 0.0 && g.extent.1 > 0.0 && g.extent.0.is_finite() && g.extent.1.is_finite()) {
        return Err("`extent` must be two positive lengths".into());
    }
    if !(g.fill > 0.0 && g.fill <= 1.0) {
        return Err(format!("`fill` must be in (0, 1], not {}", g.fill));
    }
    if !((0.0..1.0).contains(&g.color_jitter) && (0.0..=30.0).contains(&g.decades)) {
        return Err("`color_jitter` must be in [0, 1) and `decades` in [0, 30]".into());
    }
    let count = g.rows as u64 * g.cols as u64;
    // Each lamp is a light description now, and two triangles and a light once built.
    let per_lamp = std::mem::size_of::<LightDesc>() as u64 + 2 * BYTES_PER_TRIANGLE + BYTES_PER_LIGHT;
    check_memory(count.saturating_mul(per_lamp), format_args!("a grid of {} × {} lamps", g.rows, g.cols))?;
    let cell = (g.extent.0 / g.cols as f32, g.extent.1 / g.rows as f32);
    let side = g.fill.sqrt();
    let lamp = (cell.0 * side, cell.1 * side);
    let area = lamp.0 * lamp.1;
    let (e1, e2) = (tangent * lamp.0, bitangent * lamp.1);
    let center = Vec3A::from(g.center);
    let origin = center - tangent * (0.5 * g.extent.0) - bitangent * (0.5 * g.extent.1);

    // Per-lamp colour factor with the given jitter and log-uniform spread, then a rescale so
    // the requested mean or total holds exactly.
    let factors: Vec<Rgb> = (0..count)
        .map(|i| {
            let jitter = |c: u64| 1.0 + g.color_jitter * (2.0 * grid_random(g.seed, i, c) - 1.0);
            let spread = 10f32.powf(g.decades * grid_random(g.seed, i, 3));
            Rgb::new(jitter(0), jitter(1), jitter(2)) * spread
        })
        .collect();
    let sides = if g.two_sided { 2.0 } else { 1.0 };
    // The mean colour and the mean lamp luminance the result must have.
    let (color, target_lum) = match &g.emission {
        GridEmission::Radiance { rgb } => (Rgb::from(*rgb), luminance(Rgb::from(*rgb))),
        GridEmission::Power { watts, color } => {
            if !(*watts > 0.0) {
                return Err("`Power` needs positive `watts`".into());
            }
            // Σ π·A·Y(L_i)·sides = watts.
            (Rgb::from(*color), *watts / (std::f32::consts::PI * area * sides * count as f32))
        }
    };
    if !(color.min_element() >= 0.0 && luminance(color) > 0.0 && color.is_finite()) {
        return Err("the grid's colour must be non-negative with positive luminance".into());
    }
    let mean_lum = factors.iter().map(|f| luminance(color * *f) as f64).sum::<f64>() / count as f64;
    let scale = (target_lum as f64 / mean_lum) as f32;
    let label: Arc<str> = Arc::from(name);
    let lights = (0..count)
        .map(|i| {
            let (row, col) = ((i / g.cols as u64) as f32, (i % g.cols as u64) as f32);
            let cell_center = origin + tangent * ((col + 0.5) * cell.0) + bitangent * ((row + 0.5) * cell.1);
            LightDesc::Quad {
                name: label.clone(),
                corner: cell_center - 0.5 * (e1 + e2),
                edge1: e1,
                edge2: e2,
                radiance: color * factors[i as usize] * scale,
                two_sided: g.two_sided,
            }
        })
        .collect();
    Ok(lights)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    fn grid(rows: u32, emission: GridEmission) -> GridSpec {
        GridSpec {
            center: [0.0, 2.0, 0.0],
            normal: [0.0, -1.0, 0.0],
            tangent: None,
            extent: (1.2, 1.2),
            rows,
            cols: rows,
            fill: 0.25,
            emission,
            color_jitter: 0.15,
            decades: 2.0,
            seed: 3,
            two_sided: false,
        }
    }

    fn total_power(lights: &[LightDesc]) -> f32 {
        lights
            .iter()
            .map(|l| match l {
                LightDesc::Quad { edge1, edge2, radiance, .. } => {
                    PI * edge1.cross(*edge2).length() * luminance(*radiance)
                }
                _ => 0.0,
            })
            .sum()
    }

    #[test]
    fn grid_power_is_constant_across_sizes_and_lamps_face_the_normal() {
        for rows in [5, 9, 32] {
            let lights =
                light_grid("g", &grid(rows, GridEmission::Power { watts: 45.0, color: [1.0, 0.9, 0.8] })).unwrap();
            assert_eq!(lights.len(), (rows * rows) as usize);
            assert!((total_power(&lights) - 45.0).abs() < 45.0 * 1e-4, "{rows}");
            for l in &lights {
                let LightDesc::Quad { corner, edge1, edge2, .. } = l else { unreachable!() };
                assert!(edge1.cross(*edge2).normalize().dot(Vec3A::NEG_Y) > 0.999);
                assert!((corner.y - 2.0).abs() < 1e-6 && corner.x >= -0.6 - 1e-6 && corner.x <= 0.6);
            }
        }
    }

    #[test]
    fn grid_radiance_mean_is_exact_and_spread_spans_decades() {
        let lights = light_grid("g", &grid(20, GridEmission::Radiance { rgb: [40.0; 3] })).unwrap();
        let lums: Vec<f32> = lights
            .iter()
            .map(|l| match l {
                LightDesc::Quad { radiance, .. } => luminance(*radiance),
                _ => 0.0,
            })
            .collect();
        let mean = lums.iter().sum::<f32>() / lums.len() as f32;
        assert!((mean - 40.0).abs() < 1e-2, "{mean}");
        let (lo, hi) = lums.iter().fold((f32::MAX, 0.0f32), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(hi / lo > 50.0 && hi / lo <= 100.0 * 1.15 * 1.15 / 0.85, "{lo} {hi}");
    }

    #[test]
    fn bad_grids_are_explained() {
        let mut g = grid(5, GridEmission::Radiance { rgb: [1.0; 3] });
        g.fill = 0.0;
        assert!(light_grid("g", &g).unwrap_err().contains("fill"));
        let mut g = grid(5, GridEmission::Radiance { rgb: [1.0; 3] });
        g.normal = [0.0; 3];
        assert!(light_grid("g", &g).unwrap_err().contains("normal"));
    }

    #[test]
    fn box_faces_point_outwards() {
        let b = box_mesh("b", Vec3A::new(1.0, 2.0, 3.0), 0);
        assert_eq!(b.triangles.len(), 12);
        for t in &b.triangles {
            let [a, bb, c] = t.map(|i| b.positions[i as usize]);
            let n = (bb - a).cross(c - a);
            assert!(n.dot((a + bb + c) / 3.0) > 0.0);
        }
    }

    #[test]
    fn sphere_is_round_and_outward() {
        let s = sphere_mesh("s", Vec3A::ONE, 2.0, 2, 0);
        assert_eq!(s.triangles.len(), 20 * 16);
        for t in &s.triangles {
            let [a, b, c] = t.map(|i| s.positions[i as usize]);
            assert!((b - a).cross(c - a).dot(a - Vec3A::ONE) > 0.0);
        }
        assert!(s.positions.iter().all(|p| ((*p - Vec3A::ONE).length() - 2.0).abs() < 1e-5));
    }
}
