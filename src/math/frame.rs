//! Orthonormal shading frame: world ↔ local coordinates with the normal as +Z.
//!
//! Built with the branchless construction of Duff et al. 2017, "Building an Orthonormal Basis,
//! Revisited" (JCGT 6(1)), which has no singularity and no normalisation.

use super::Vec3A;

/// An orthonormal basis (s, t, n); local +Z is `n`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3A,
    /// Second tangent.
    pub t: Vec3A,
    /// Normal (local +Z).
    pub n: Vec3A,
}

impl Frame {
    /// A frame around the unit vector `n`.
    #[inline]
    pub fn from_normal(n: Vec3A) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// A frame around the unit vector `n` whose first tangent is the unit vector `t`, taken
    /// perpendicular to `n`.
    #[inline]
    pub fn from_normal_tangent(n: Vec3A, t: Vec3A) -> Self {
        match (t - n * n.dot(t)).try_normalize() {
            Some(s) => Self { s, t: n.cross(s), n },
            None => Self::from_normal(n),
        }
    }

    /// World direction to local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local direction to world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_round_trips() {
        let dirs = [
            Vec3A::Z,
            -Vec3A::Z,
            Vec3A::X,
            Vec3A::new(0.3, -0.4, 0.5).normalize(),
            Vec3A::new(1e-7, 0.0, -1.0).normalize(),
        ];
        for n in dirs {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5);
            assert!((f.s.cross(f.t) - n).length() < 1e-5, "right-handed");
            let v = Vec3A::new(0.2, 0.7, -0.1);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}
