//! Fixed-point integers for sums that must not depend on the order of their terms: integer
//! addition is associative where float addition is not, so sums of the same terms split into
//! any parts and added in any order are the same bits (the film's pixel sums, a learning
//! light sampler's statistics).

/// Fixed-point conversions of samples: what the film sums (and a learning light sampler).
pub struct Fixed;

impl Fixed {
    /// Fractional bits of a value.
    pub const VALUE: i32 = 62;
    /// Fractional bits of a squared value.
    pub const SQUARE: i32 = 32;
    /// Largest magnitude a sample keeps.
    pub const LIMIT: f64 = (1u64 << 31) as f64;

    /// `x` × 2^`frac`, truncated towards zero, as an integer; `x` clamped to ±2³¹ (±LIMIT²
    /// for a square), NaN as 0. Exact bit arithmetic on the f64, no float-to-i128 call.
    #[inline]
    pub fn of(x: f64, frac: i32, limit: f64) -> i128 {
        let x = if x.is_nan() { 0.0 } else { x.clamp(-limit, limit) };
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        if exp == 0 {
            return 0; // zero or subnormal: far below the resolution
        }
        let mantissa = ((bits & ((1 << 52) - 1)) | (1 << 52)) as i128;
        // x = mantissa · 2^(exp − 1075)
        let shift = exp - 1075 + frac;
        let q = if shift >= 0 {
            mantissa << shift
        } else if shift > -64 {
            mantissa >> -shift
        } else {
            0
        };
        if bits >> 63 != 0 { -q } else { q }
    }

    /// A fixed-point integer with `frac` fractional bits back as a float.
    #[inline]
    pub fn to_f64(q: i128, frac: i32) -> f64 {
        q as f64 * (-frac as f64).exp2()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_keeps_values_to_its_resolution() {
        for x in [1.0f64, -2.5, 1e-12, 3.0e9, -7.25e-3, 0.1] {
            let q = Fixed::of(x, Fixed::VALUE, Fixed::LIMIT);
            let back = Fixed::to_f64(q, Fixed::VALUE);
            let expect = x.clamp(-Fixed::LIMIT, Fixed::LIMIT);
            assert!((back - expect).abs() <= 2f64.powi(-Fixed::VALUE) + 1e-15 * expect.abs(), "{x}: {back}");
        }
        assert_eq!(Fixed::of(f64::NAN, Fixed::VALUE, Fixed::LIMIT), 0);
        assert_eq!(Fixed::of(0.0, Fixed::VALUE, Fixed::LIMIT), 0);
    }
}
