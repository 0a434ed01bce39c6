//! Chains of refractions through smooth glass: where the vertices are (Newton's method on the
//! half-vector constraints, each vertex moved in its triangle's plane and put back on the
//! glass by a ray), and what a solved chain passes on and how densely (the generalised
//! geometry term for area lights, the density of a delta light's directions or beam).
//! Derivatives are forward differences in f64; the implicit function theorem turns them into
//! how the chain follows when one of its ends moves.

use glam::DVec3;

use super::super::{RayCounters, transmittance};
use super::MAX_CASTERS;
use crate::geometry::{Ray, SurfaceHit, TriangleRef, offset_toward};
use crate::material::SmoothGlass;
use crate::math::{Rgb, Vec3A};
use crate::scene::Scene;
/// Newton steps before a chain is given up.
const MAX_ITERATIONS: u32 = 40;
/// A chain is solved when every vertex's half vector is within this sine of its normal
/// (Cycles' figure; 10⁻⁴ took 1.1× the CPU on glass.glb for the same error).
const TOLERANCE: f64 = 1e-3;
/// How much further from solved a Newton step may leave a chain ([`solve_chain`]).
const GROWTH: f64 = 2.0;
/// Smallest step fraction the line search tries before giving up.
const MIN_STEP: f64 = 1.0 / 1024.0;
/// Most surfaces a seed segment may cross.
const MAX_SEED_HITS: usize = 16;

/// One refraction of a chain: a point on a triangle of smooth glass.
#[derive(Clone, Copy, Debug)]
pub(super) struct Vertex {
    /// The point.
    pub(super) x: DVec3,
    /// Its triangle's first corner and the two edges from it scaled so that their dot
    /// products with a point's offset give its barycentrics, and the corners' shading normals.
    origin: DVec3,
    to_b1: DVec3,
    to_b2: DVec3,
    normals: [DVec3; 3],
    /// The triangle's front normal and two tangents with it an orthonormal frame: the plane
    /// Newton's steps move the point in.
    pub(super) n_geom: DVec3,
    s: DVec3,
    t: DVec3,
    /// The glass, and its material's index.
    glass: SmoothGlass,
    material: u32,
}

impl Vertex {
    /// The vertex at `p` on `triangle`, of `material`, smooth glass `glass`.
    fn new(scene: &Scene, triangle: TriangleRef, p: Vec3A, material: u32, glass: SmoothGlass) -> Self {
        let c = scene.geometry.corners(triangle);
        let n_geom = to_f64(c.n_geom);
        let (s, t) = n_geom.any_orthonormal_pair();
        let [p0, p1, p2] = c.p.map(to_f64);
        let (e1, e2) = (p1 - p0, p2 - p0);
        let n = e1.cross(e2) / e1.cross(e2).length_squared();
        // b1 = (d × e2)·n = d·(e2 × n), b2 = (e1 × d)·n = d·(n × e1).
        let (to_b1, to_b2) = (e2.cross(n), n.cross(e1));
        Self { x: to_f64(p), origin: p0, to_b1, to_b2, normals: c.n.map(to_f64), n_geom, s, t, glass, material }
    }

    /// The vertex at `hit`, on smooth glass `glass`.
    fn at(scene: &Scene, hit: &SurfaceHit, glass: SmoothGlass) -> Self {
        Self::new(scene, hit.triangle, hit.p, hit.material, glass)
    }

    /// The shading normal at `x` (in the triangle's plane, perhaps beyond its edges):
    /// the corners' normals interpolated linearly, so that it changes smoothly under a step.
    fn normal_at(&self, x: DVec3) -> DVec3 {
        let d = x - self.origin;
        let (b1, b2) = (d.dot(self.to_b1), d.dot(self.to_b2));
        (self.normals[0] * (1.0 - b1 - b2) + self.normals[1] * b1 + self.normals[2] * b2).normalize_or_zero()
    }

    /// The index of refraction on the side of the surface `w` points to.
    fn ior_towards(&self, w: DVec3) -> f64 {
        if w.dot(self.n_geom) > 0.0 { 1.0 } else { self.glass.ior as f64 }
    }

    /// How far the vertex at `x` is from refracting the unit direction `wo` (towards the
    /// receiver) into `wi` (towards the light): the generalised half vector's components
    /// across the shading normal, zero where Snell's law holds.
    fn constraint(&self, x: DVec3, wo: DVec3, wi: DVec3) -> [f64; 2] {
        let h = (wo * self.ior_towards(wo) + wi * self.ior_towards(wi)).normalize_or_zero();
        let c = h.cross(self.normal_at(x));
        [c.dot(self.s), c.dot(self.t)]
    }
}

/// Unknowns of a chain: two per vertex.
const N: usize = 2 * MAX_CASTERS;

/// Where a chain's light is: a point (on an emissive surface, or a point or spot light), a
/// point on a disk lamp that turns to face whoever sees it, or the direction towards a
/// directional light.
#[derive(Clone, Copy, Debug)]
pub(super) enum End {
    /// An emissive surface's point, or a point or spot light's.
    Point(DVec3),
    /// The point `offset` from `centre` on a disk across `towards` (unit), the disk turned
    /// (by the least rotation) to face whoever sees it: Blender's soft-falloff lamp, whose
    /// disk faces each receiver. Offsets measure its area.
    Facing { centre: DVec3, towards: DVec3, offset: DVec3 },
    /// The unit direction towards a directional light.
    Direction(DVec3),
}

impl End {
    /// The light's point as seen from `x`; `None` for a directional light.
    pub(super) fn point_from(self, x: DVec3) -> Option<DVec3> {
        match self {
            End::Point(y) => Some(y),
            End::Facing { centre, towards, offset } => {
                Some(centre + turned(offset, towards, (x - centre).normalize_or_zero()))
            }
            End::Direction(_) => None,
        }
    }

    /// The unit direction from `x` towards the light.
    pub(super) fn seen_from(self, x: DVec3) -> DVec3 {
        match (self, self.point_from(x)) {
            (End::Direction(d), _) => d,
            (_, y) => (y.unwrap_or(x) - x).normalize_or_zero(),
        }
    }

    /// The light moved by `d` (a point, or a disk's offset); a direction stays.
    fn moved(self, d: DVec3) -> End {
        match self {
            End::Point(y) => End::Point(y + d),
            End::Facing { centre, towards, offset } => End::Facing { centre, towards, offset: offset + d },
            End::Direction(_) => self,
        }
    }
}

/// `v` (across the unit `from`) turned by the least rotation that takes `from` to the unit
/// `to` (Rodrigues' formula about from × to); undefined only for opposite directions.
pub(super) fn turned(v: DVec3, from: DVec3, to: DVec3) -> DVec3 {
    let axis = from.cross(to);
    let cos = from.dot(to);
    if cos <= -1.0 + 1e-12 {
        return -v;
    }
    v + axis.cross(v) + axis.cross(axis.cross(v)) / (1.0 + cos)
}

/// A chain of refractions from the receiver `x0` to the light at `end`.
#[derive(Clone, Copy)]
pub(super) struct Chain {
    pub(super) x0: DVec3,
    pub(super) end: End,
    v: [Option<Vertex>; MAX_CASTERS],
    pub(super) k: usize,
}

impl Chain {
    pub(super) fn vertex(&self, i: usize) -> &Vertex {
        self.v[i].as_ref().expect("a vertex below k")
    }

    /// The unit direction the chain leaves the receiver in.
    pub(super) fn first_direction(&self) -> DVec3 {
        (self.vertex(0).x - self.x0).normalize()
    }

    /// The unit directions at vertex `i` (at `xs[i]`) towards the receiver at `x0` and
    /// towards the light at `end`, through the vertices at `xs`.
    fn directions(&self, x0: DVec3, xs: &[DVec3; MAX_CASTERS], end: End, i: usize) -> (DVec3, DVec3) {
        let before = if i == 0 { x0 } else { xs[i - 1] };
        let wi = if i + 1 == self.k { end.seen_from(xs[i]) } else { (xs[i + 1] - xs[i]).normalize_or_zero() };
        ((before - xs[i]).normalize_or_zero(), wi)
    }

    /// Every vertex's constraint with the receiver at `x0`, the vertices at `xs` and the
    /// light at `end`.
    fn residual_at(&self, x0: DVec3, xs: &[DVec3; MAX_CASTERS], end: End) -> [f64; N] {
        let mut c = [0.0; N];
        for i in 0..self.k {
            let (wo, wi) = self.directions(x0, xs, end, i);
            let [a, b] = self.vertex(i).constraint(xs[i], wo, wi);
            (c[2 * i], c[2 * i + 1]) = (a, b);
        }
        c
    }

    /// Every vertex's constraint with the vertices at `xs`.
    fn residual(&self, xs: &[DVec3; MAX_CASTERS]) -> [f64; N] {
        self.residual_at(self.x0, xs, self.end)
    }

    fn positions(&self) -> [DVec3; MAX_CASTERS] {
        std::array::from_fn(|i| self.v[i].map_or(DVec3::ZERO, |v| v.x))
    }

    /// Forward-difference step for moving `x`: small against the scene's coordinates (the
    /// truncation error is the step over the segments' lengths, 10⁻⁶ relative for metres)
    /// yet far above f64 round-off.
    fn step(x: DVec3) -> f64 {
        1e-6 * (1.0 + x.abs().max_element())
    }

    /// ∂residual/∂(vertex j along its s, t), as columns 2j and 2j + 1, given the residual
    /// `base` where the chain is.
    fn jacobian(&self, base: &[f64; N]) -> [[f64; N]; N] {
        let xs = self.positions();
        let mut jac = [[0.0; N]; N];
        for j in 0..self.k {
            let v = self.vertex(j);
            let h = Self::step(v.x);
            for (axis, dir) in [v.s, v.t].into_iter().enumerate() {
                let mut moved = xs;
                moved[j] += dir * h;
                let c = self.residual(&moved);
                for (r, row) in jac.iter_mut().enumerate().take(2 * self.k) {
                    row[2 * j + axis] = (c[r] - base[r]) / h;
                }
            }
        }
        jac
    }

    /// How the first vertex's coordinates (s₁, t₁) move as one end of the solved chain
    /// moves along `a` and `b` (the light point, or with `receiver` the receiver), the
    /// vertices following so that the constraints stay met: −J⁻¹ ∂residual/∂end, by the
    /// implicit function theorem, for all vertices (rows 2i, 2i + 1 for vertex i).
    fn follow(&self, a: DVec3, b: DVec3, receiver: bool) -> Option<[[f64; 2]; N]> {
        let xs = self.positions();
        let base = self.residual(&xs);
        let last = xs[self.k - 1];
        let at = if receiver { self.x0 } else { self.end.point_from(last)? };
        let h = Self::step(at);
        let mut minus = [[0.0; 2]; N];
        for (col, dir) in [a, b].into_iter().enumerate() {
            let c = if receiver {
                self.residual_at(self.x0 + dir * h, &xs, self.end)
            } else {
                self.residual_at(self.x0, &xs, self.end.moved(dir * h))
            };
            for (r, row) in minus.iter_mut().enumerate().take(2 * self.k) {
                row[col] = -(c[r] - base[r]) / h;
            }
        }
        solve(self.jacobian(&base), minus, 2 * self.k)
    }
}

/// The largest of the first `n / 2` vertices' constraint lengths (whatever frame each
/// vertex's two components are in: a step onto another triangle turns it).
fn norm(c: &[f64; N], n: usize) -> f64 {
    c[..n].chunks(2).fold(0.0f64, |m, v| m.max(v[0].hypot(v[1])))
}

/// Solves `a · x = b` for the leading `n` × `n` block of `a` with `M` right-hand sides, by
/// Gaussian elimination with partial pivoting; `None` when `a` is singular there.
// Elimination reads as the textbook's indices; iterators over two rows at once would not.
#[allow(clippy::needless_range_loop)]
fn solve<const M: usize>(mut a: [[f64; N]; N], mut b: [[f64; M]; N], n: usize) -> Option<[[f64; M]; N]> {
    let scale = (0..n).flat_map(|r| (0..n).map(move |c| (r, c))).fold(0.0f64, |m, (r, c)| m.max(a[r][c].abs()));
    for col in 0..n {
        let pivot = (col..n).max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))?;
        if !(a[pivot][col].abs() > 1e-12 * scale) {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for r in col + 1..n {
            let f = a[r][col] / a[col][col];
            for c in col..n {
                a[r][c] -= f * a[col][c];
            }
            for c in 0..M {
                b[r][c] -= f * b[col][c];
            }
        }
    }
    for col in (0..n).rev() {
        for c in 0..M {
            let mut v = b[col][c];
            for k in col + 1..n {
                v -= a[col][k] * b[k][c];
            }
            b[col][c] = v / a[col][col];
        }
    }
    Some(b)
}

pub(super) fn to_f32(v: DVec3) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

pub(super) fn to_f64(v: Vec3A) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// The ray from `origin` to the light at `end` and how far along it the light is.
fn ray_to(origin: Vec3A, end: End) -> (Ray, f32) {
    match end.point_from(to_f64(origin)) {
        Some(y) => (Ray::new(origin, to_f32(y) - origin), 1.0),
        None => (Ray::new(origin, to_f32(end.seen_from(to_f64(origin)))), f32::INFINITY),
    }
}

/// The ray from a point on a surface of front normal `n` to the light at `end`, leaving on
/// the side it heads to, and how far along it the light is.
pub(super) fn ray_from_surface(from: Vec3A, n: Vec3A, end: End) -> (Ray, f32) {
    let towards = to_f32(end.seen_from(to_f64(from)));
    ray_to(offset_toward(from, n, towards), end)
}

/// The smooth glass `hit` is on, if it is.
fn glass_at(scene: &Scene, hit: &SurfaceHit) -> Option<SmoothGlass> {
    scene.materials[hit.material as usize].smooth_glass()
}

/// What the straight way from a receiver to a light meets. (Returned once per light sample
/// and never stored: boxing the chain would allocate on every connection.)
#[allow(clippy::large_enum_variant)]
pub(super) enum Straight {
    /// Nothing: the light is in plain sight.
    Clear,
    /// Something other than smooth glass, or more smooth glass than a chain may cross.
    Blocked,
    /// Smooth glass alone: the chain solved from its refractions, `None` where Newton's method
    /// found none.
    Glass(Option<Chain>),
}

/// The refractions the straight way from the receiver at `p` (its ray `origin`) to the light
/// at `end` makes, at most `most` of them.
fn seed(scene: &Scene, p: Vec3A, origin: Vec3A, end: End, most: usize, counters: &mut RayCounters) -> Straight {
    let mut chain = Chain { x0: to_f64(p), end, v: [None; MAX_CASTERS], k: 0 };
    let (mut ray, t_max) = ray_to(origin, end);
    for _ in 0..MAX_SEED_HITS {
        counters.rays += 1;
        let Some(hit) = scene.intersect(&ray, t_max) else {
            return if chain.k > 0 { Straight::Glass(Some(chain)) } else { Straight::Clear };
        };
        let Some(glass) = glass_at(scene, &hit).filter(|_| chain.k < most) else { return Straight::Blocked };
        chain.v[chain.k] = Some(Vertex::at(scene, &hit, glass));
        chain.k += 1;
        ray = ray_from_surface(hit.p, hit.n_geom, end).0;
    }
    Straight::Blocked
}

/// The chain with vertex `i` onwards moved to where rays towards `proposed` meet the same
/// glass, or `None` where one meets something else or nothing.
fn reproject(
    scene: &Scene,
    chain: &Chain,
    origin: Vec3A,
    proposed: &[DVec3; MAX_CASTERS],
    counters: &mut RayCounters,
) -> Option<Chain> {
    let mut next = *chain;
    for (i, &at) in proposed.iter().enumerate().take(chain.k) {
        let ray = if i == 0 {
            ray_to(origin, End::Point(at)).0
        } else {
            let prev = next.vertex(i - 1);
            ray_from_surface(to_f32(prev.x), to_f32(prev.n_geom), End::Point(at)).0
        };
        counters.rays += 1;
        // Twice the distance: the proposal lies off the surface, on either side of it.
        let hit = scene.intersect(&ray, 2.0)?;
        if hit.material != chain.vertex(i).material {
            return None;
        }
        next.v[i] = Some(Vertex::at(scene, &hit, chain.vertex(i).glass));
    }
    Some(next)
}

/// Newton's method on the chain's constraints with a backtracking line search: each step
/// moves every vertex in its triangle's plane and puts it back on the glass by a ray. A step
/// may leave the constraints up to [`GROWTH`] times further from zero (a vertex that crosses
/// onto another triangle turns its constraint's frame and meets other normals; insisting on
/// a decrease cost 1.2× the time on `factors/bulb_clear.glb` for the same solutions).
fn solve_chain(scene: &Scene, mut chain: Chain, origin: Vec3A, counters: &mut RayCounters) -> Option<Chain> {
    let n = 2 * chain.k;
    let mut residual = chain.residual(&chain.positions());
    let mut lambda = 1.0;
    for _ in 0..MAX_ITERATIONS {
        let size = norm(&residual, n);
        if size < TOLERANCE {
            return Some(chain);
        }
        let rhs: [[f64; 1]; N] = std::array::from_fn(|r| [-residual[r]]);
        let delta = solve(chain.jacobian(&residual), rhs, n)?;
        loop {
            let xs = chain.positions();
            let proposed: [DVec3; MAX_CASTERS] = std::array::from_fn(|i| match chain.v[i] {
                Some(v) => xs[i] + (v.s * delta[2 * i][0] + v.t * delta[2 * i + 1][0]) * lambda,
                None => DVec3::ZERO,
            });
            let moved = reproject(scene, &chain, origin, &proposed, counters);
            let better = moved.map(|m| (m, m.residual(&m.positions()))).filter(|(_, r)| norm(r, n) < GROWTH * size);
            if let Some((m, r)) = better {
                (chain, residual) = (m, r);
                lambda = (2.0 * lambda).min(1.0);
                break;
            }
            lambda *= 0.5;
            if lambda < MIN_STEP {
                return None;
            }
        }
    }
    None
}

/// Whether every vertex of a solved chain refracts: the two directions on opposite sides of
/// both its triangle and its shading normal.
fn refracts_everywhere(chain: &Chain) -> bool {
    let xs = chain.positions();
    (0..chain.k).all(|i| {
        let v = chain.vertex(i);
        let (wo, wi) = chain.directions(chain.x0, &xs, chain.end, i);
        let n = v.normal_at(v.x);
        wo.dot(v.n_geom) * wi.dot(v.n_geom) < 0.0 && wo.dot(n) * wi.dot(n) < 0.0
    })
}

/// The solved chain's density of the receiver's direction per unit area of the light:
/// |det ∂ω₀/∂y| with y moving in the light's plane (normal `n_y`).
pub(super) fn geometry_term(chain: &Chain, n_y: DVec3) -> Option<f64> {
    let (a, b) = n_y.any_orthonormal_pair();
    // ∂(s₁, t₁ of the first vertex)/∂(y along a, b).
    let d = chain.follow(a, b, false)?;
    let v1 = chain.vertex(0);
    let to_first = v1.x - chain.x0;
    let r = to_first.length();
    let (e1, e2) = (to_first / r).any_orthonormal_pair();
    let dx = |col: usize| v1.s * d[0][col] + v1.t * d[1][col];
    let (da, db) = (dx(0), dx(1));
    let det = (e1.dot(da) * e2.dot(db) - e1.dot(db) * e2.dot(da)) / (r * r);
    det.is_finite().then_some(det.abs())
}

/// The solved chain's density, at the receiver, of a delta light's light at its end: how
/// much of a point light's directions (|det ∂ω_L/∂x₀|) or of a directional light's beam
/// cross-section (|det ∂x_k/∂x₀| across the beam) falls on unit area across the first
/// direction ω₀, the receiver moving across it and the chain following. Without glass
/// this is 1/d² and 1.
pub(super) fn delta_density(chain: &Chain) -> Option<f64> {
    let (a, b) = chain.first_direction().any_orthonormal_pair();
    let d = chain.follow(a, b, true)?;
    let (i, last) = (chain.k - 1, chain.vertex(chain.k - 1));
    let dx = |col: usize| last.s * d[2 * i][col] + last.t * d[2 * i + 1][col];
    let (da, db) = (dx(0), dx(1));
    let (axis, scale) = match chain.end {
        End::Point(y) => {
            let r = (last.x - y).length();
            ((last.x - y) / r, 1.0 / (r * r))
        }
        End::Direction(w) => (w, 1.0),
        End::Facing { .. } => return None,
    };
    let (e1, e2) = axis.any_orthonormal_pair();
    let det = (e1.dot(da) * e2.dot(db) - e1.dot(db) * e2.dot(da)) * scale;
    det.is_finite().then_some(det.abs())
}

/// The index of refraction around the chain's light: the glass's when it lies inside the
/// glass, else 1.
pub(super) fn ior_at_light(chain: &Chain) -> f64 {
    let last = chain.vertex(chain.k - 1);
    last.ior_towards(chain.end.seen_from(last.x))
}

/// What the glass along a chain passes on from the light point to the receiver (Fresnel and
/// tint at each refraction, absorption on the way through), and the probability that BSDF
/// sampling refracts at every vertex.
pub(super) fn passage(chain: &Chain) -> (Rgb, f32) {
    let (mut through, mut probability) = (Rgb::ONE, 1.0);
    let xs = chain.positions();
    for i in 0..chain.k {
        let v = chain.vertex(i);
        let (wo, wi) = chain.directions(chain.x0, &xs, chain.end, i);
        let cos_o = wo.dot(v.normal_at(v.x)).abs() as f32;
        let eta = (v.ior_towards(wi) / v.ior_towards(wo)) as f32;
        through *= v.glass.transmittance(cos_o, eta);
        probability *= v.glass.refraction_probability(cos_o, eta);
        if wi.dot(v.n_geom) < 0.0 && v.glass.absorption != Rgb::ZERO {
            let length = match (i + 1 == chain.k, chain.end.point_from(v.x)) {
                (false, _) => (xs[i + 1] - v.x).length(),
                (true, Some(y)) => (y - v.x).length(),
                // A directional light seen from inside the glass: it is no way out.
                (true, None) => return (Rgb::ZERO, 0.0),
            };
            through *= transmittance(v.glass.absorption, length as f32);
        }
    }
    (through, probability)
}

/// Where a chain from the receiver at `p` to the point `y` (front normal `n_y`) on an
/// emissive surface ends: just off the surface on `p`'s side. A function of the two points
/// alone: BSDF sampling asks the connection whether it would have found a path it found.
pub(super) fn surface_end(p: Vec3A, y: Vec3A, n_y: Vec3A) -> End {
    End::Point(to_f64(offset_toward(y, n_y, p - y)))
}

/// What the straight way from the receiver at `p` (geometric normal `n_p`) to the light at
/// `end` meets; where that is smooth glass alone, at most `most` refractions of it, the chain
/// solved from them.
pub(super) fn walk(scene: &Scene, p: Vec3A, n_p: Vec3A, end: End, most: usize, counters: &mut RayCounters) -> Straight {
    let towards = to_f32(end.seen_from(to_f64(p)));
    let origin = offset_toward(p, n_p, towards);
    match seed(scene, p, origin, end, most, counters) {
        Straight::Glass(Some(chain)) => {
            Straight::Glass(solve_chain(scene, chain, origin, counters).filter(refracts_everywhere))
        }
        other => other,
    }
}

/// The chain of at most `most` refractions through smooth glass from the receiver at `p`
/// (geometric normal `n_p`) to the light at `end`, seeded by the straight way and solved.
pub(super) fn connect_to(
    scene: &Scene,
    p: Vec3A,
    n_p: Vec3A,
    end: End,
    most: usize,
    counters: &mut RayCounters,
) -> Option<Chain> {
    match walk(scene, p, n_p, end, most, counters) {
        Straight::Glass(chain) => chain,
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::math::Mat4;
    use crate::scene::description::{InstanceDesc, SceneDescription};
    use crate::scene::shapes::{quad_mesh, sphere_mesh};
    use crate::scene::{BuildOptions, build};

    /// A smooth glass ball (radius 0.5, centre 0.8 m up) over a floor, with an emissive
    /// quad: the scene the chains below cross.
    fn ball_scene() -> Scene {
        let glass = Material { transmission: 1.0, roughness: 0.0, ior: 1.5, ..Material::diffuse("glass", Rgb::ONE) };
        let lamp = Material { emission: Rgb::ONE, ..Material::diffuse("lamp", Rgb::ZERO) };
        let mut desc = SceneDescription {
            source: "<test>".into(),
            materials: vec![Material::diffuse("floor", Rgb::splat(0.5)), glass, lamp],
            ..Default::default()
        };
        desc.meshes.push(quad_mesh("floor", Vec3A::new(-3.0, 0.0, -3.0), Vec3A::Z * 6.0, Vec3A::X * 6.0, 0));
        desc.meshes.push(sphere_mesh("ball", Vec3A::new(0.0, 0.8, 0.0), 0.5, 5, 1));
        desc.meshes.push(quad_mesh("lamp", Vec3A::new(-0.15, 1.6, -0.15), Vec3A::X * 0.3, Vec3A::Z * 0.3, 2));
        for mesh in 0..3 {
            desc.instances.push(InstanceDesc { mesh, transform: Mat4::IDENTITY, name: format!("{mesh}") });
        }
        let opts = BuildOptions { frame_without_camera: true, ..Default::default() };
        build(desc, &opts).expect("the test scene builds").0
    }

    /// Snell's law at every vertex of a solved chain, checked with angles.
    fn assert_refracts(chain: &Chain) {
        for i in 0..chain.k {
            let v = chain.vertex(i);
            let n = v.normal_at(v.x);
            let (wo, wi) = chain.directions(chain.x0, &chain.positions(), chain.end, i);
            let sin = |w: DVec3| w.cross(n).length();
            let snell = v.ior_towards(wo) * sin(wo) - v.ior_towards(wi) * sin(wi);
            assert!(snell.abs() < 2e-3, "vertex {i}: η sin θ differ by {snell}");
            // In one plane with the normal.
            assert!(wo.cross(n).normalize().dot(wi.cross(n).normalize()) < -0.999, "vertex {i} out of plane");
        }
    }

    #[test]
    fn turning_takes_one_direction_to_the_other_and_keeps_lengths_and_right_angles() {
        let from = DVec3::new(0.3, -0.8, 0.5).normalize();
        for to in [DVec3::new(-0.2, 0.1, 0.97).normalize(), from, DVec3::new(0.9, 0.4, -0.1).normalize()] {
            let (a, b) = from.any_orthonormal_pair();
            let (ta, tb) = (turned(a, from, to), turned(b, from, to));
            assert!((ta.length() - 1.0).abs() < 1e-12 && (tb.length() - 1.0).abs() < 1e-12);
            assert!(ta.dot(to).abs() < 1e-12 && tb.dot(to).abs() < 1e-12 && ta.dot(tb).abs() < 1e-12);
            // A rotation, not a mirror: the frame keeps its handedness.
            assert!((ta.cross(tb).dot(to) - a.cross(b).dot(from)).abs() < 1e-12);
        }
    }

    #[test]
    fn chains_obey_snell_and_their_geometry_term_is_the_density_of_directions() {
        let scene = ball_scene();
        let mut counters = RayCounters::default();
        let n_y = -Vec3A::Y;
        // One point on the floor under the ball and two on the lamp (two refractions), and
        // one floor point to a point inside the ball (one).
        let cases = [
            (Vec3A::new(0.05, 0.0, 0.02), Vec3A::new(0.0, 1.6, 0.0)),
            (Vec3A::new(-0.03, 0.0, 0.06), Vec3A::new(0.01, 1.6, -0.02)),
            (Vec3A::new(0.4, 0.0, -0.2), Vec3A::new(0.02, 0.85, 0.01)),
        ];
        for (k, (p, y)) in cases.into_iter().enumerate() {
            let chain = connect_to(&scene, p, Vec3A::Y, surface_end(p, y, n_y), MAX_CASTERS, &mut counters)
                .expect("a chain through the ball");
            assert_eq!(chain.k, if k < 2 { 2 } else { 1 }, "case {k}");
            assert_refracts(&chain);
            let g = geometry_term(&chain, to_f64(n_y)).unwrap();
            // The same density by brute force: solve with the light point moved by ±h along
            // x and z, and measure the solid angle the first direction sweeps.
            let h = 2e-3;
            let mut dir = |dy: Vec3A| {
                let c = connect_to(&scene, p, Vec3A::Y, surface_end(p, y + dy, n_y), MAX_CASTERS, &mut counters)
                    .expect("a moved chain");
                c.first_direction()
            };
            let (dx, dz) = (dir(Vec3A::X * h) - dir(-Vec3A::X * h), dir(Vec3A::Z * h) - dir(-Vec3A::Z * h));
            let brute = dx.cross(dz).length() / (4.0 * (h * h) as f64);
            assert!((g / brute - 1.0).abs() < 0.05, "case {k}: G {g} against {brute} by moving the light");
        }
    }

    #[test]
    fn the_density_of_a_delta_light_through_glass_is_what_moving_the_receiver_sweeps() {
        let scene = ball_scene();
        let mut counters = RayCounters::default();
        // A point light above the ball, under the lamp (two refractions), and inside the
        // ball (one); the sun from two slants that pass the lamp (two).
        let ends = [
            End::Point(DVec3::new(0.02, 1.45, -0.01)),
            End::Point(DVec3::new(0.03, 0.8, 0.02)),
            End::Direction(DVec3::new(0.15, 1.0, 0.1).normalize()),
            End::Direction(DVec3::new(-0.2, 1.0, 0.1).normalize()),
        ];
        let p = Vec3A::new(0.06, 0.0, -0.04);
        for (k, end) in ends.into_iter().enumerate() {
            let chain = connect_to(&scene, p, Vec3A::Y, end, MAX_CASTERS, &mut counters).expect("a chain");
            assert_refracts(&chain);
            let density = delta_density(&chain).unwrap();
            // By brute force: move the receiver by ±h across the first direction (on the floor,
            // then projected: a receiver's area across ω₀ is its floor area × |cos|), solve
            // again, and measure what the light's side sweeps. 2 cm: the solves stop within
            // 10⁻³ of Snell's law, whose scatter a smaller step would measure instead.
            let h = 2e-2;
            let w0 = chain.first_direction();
            let mut swept = |d: Vec3A| {
                let c = connect_to(&scene, p + d, Vec3A::Y, end, MAX_CASTERS, &mut counters).expect("a moved chain");
                let last = c.vertex(c.k - 1).x;
                match end {
                    End::Direction(w) => last - w * last.dot(w),
                    _ => (last - end.point_from(last).expect("a point")).normalize(),
                }
            };
            let (dx, dz) = (swept(Vec3A::X * h) - swept(-Vec3A::X * h), swept(Vec3A::Z * h) - swept(-Vec3A::Z * h));
            let floor_area = 4.0 * (h * h) as f64;
            let across = floor_area * w0.y.abs();
            let brute = dx.cross(dz).length() / across;
            assert!((density / brute - 1.0).abs() < 0.05, "case {k}: density {density} against {brute}");
        }
    }
}
