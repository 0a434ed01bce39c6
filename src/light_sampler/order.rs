//! The lights laid out in space: Morton order of their centres, directional lights last.
//!
//! A sampler that maps its 64-bit number onto lights monotonically in this order turns the
//! stratification of that number over a pixel's samples (a scrambled Sobol dimension) into
//! stratification over space: neighbouring numbers pick neighbouring lights, not lights
//! neighbouring in the scene file. `local` and `cells` lay their tables out so, and `uniform`
//! and `power` choose in this order (on cornell-32x32, 160 × 120, 32 spp, 3 seeds, uniform's
//! relMSE 0.0160 in file order, 0.0144 in Morton order; cornell-9x9 0.01336 → 0.01304).

use crate::light::{Light, LightBounds, LightId};
use crate::math::Vec3A;

/// A permutation of the lights into Morton order and its inverse.
#[derive(Clone, Debug)]
pub struct SpatialOrder {
    /// Slot (Morton position) → light.
    order: Vec<u32>,
    /// Light → slot.
    slot: Vec<u32>,
}

impl SpatialOrder {
    /// The order of `lights`.
    pub fn new(lights: &[Light]) -> Self {
        Self::of(&lights.iter().map(Light::bounds).collect::<Vec<_>>())
    }

    /// The order of lights with bounds `bounds`: by the Morton code of their centres on a
    /// 1024³ grid over the centres' box, ties (and directional lights, last) by index.
    pub fn of(bounds: &[LightBounds]) -> Self {
        let (lo, hi) = crate::math::point_bounds(bounds.iter().filter(|b| !b.infinite).map(LightBounds::centroid));
        let scale = 1023.0 / (hi - lo).max(Vec3A::splat(1e-12));
        let morton = |b: &LightBounds| -> u64 {
            if b.infinite {
                return u64::MAX;
            }
            let q = ((b.centroid() - lo) * scale).max(Vec3A::ZERO).min(Vec3A::splat(1023.0));
            crate::math::morton3(q.x as u32, q.y as u32, q.z as u32)
        };
        let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
        order.sort_by_key(|&i| (morton(&bounds[i as usize]), i));
        let mut slot = vec![0u32; bounds.len()];
        for (s, &l) in order.iter().enumerate() {
            slot[l as usize] = s as u32;
        }
        Self { order, slot }
    }

    /// Number of lights.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// The light in slot `slot`.
    #[inline]
    pub fn light_at(&self, slot: usize) -> LightId {
        LightId(self.order[slot])
    }

    /// The slot of `light`.
    #[inline]
    pub fn slot_of(&self, light: LightId) -> usize {
        self.slot[light.0 as usize] as usize
    }

    /// The lights' `values`, indexed by light, rearranged into slot order.
    pub fn arrange<T: Copy>(&self, values: &[T]) -> Vec<T> {
        self.order.iter().map(|&l| values[l as usize]).collect()
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        (self.order.capacity() + self.slot.capacity()) * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{DistantLight, PointLight};
    use crate::math::Rgb;

    #[test]
    fn neighbours_in_space_are_neighbours_in_the_order() {
        // A 4 × 4 grid listed row by row, a sun first: the order visits 2 × 2 blocks in turn
        // and puts the sun last; the permutation and its inverse agree.
        let mut lights = vec![Light::Distant(DistantLight { direction: -Vec3A::Y, irradiance: Rgb::ONE })];
        for i in 0..16 {
            let position = Vec3A::new((i % 4) as f32, 2.0, (i / 4) as f32);
            lights.push(Light::Point(PointLight { position, intensity: Rgb::ONE }));
        }
        let order = SpatialOrder::new(&lights);
        assert_eq!(order.light_at(16), LightId(0), "directional last");
        let first_block: Vec<u32> = (0..4).map(|s| order.light_at(s).0).collect();
        assert_eq!(first_block, vec![1, 2, 5, 6], "the 2 × 2 block at the grid's corner first");
        for l in 0..lights.len() as u32 {
            assert_eq!(order.light_at(order.slot_of(LightId(l))), LightId(l));
        }
        assert_eq!(
            order.arrange(&(0..17).collect::<Vec<u32>>()),
            (0..17).map(|s| order.light_at(s).0).collect::<Vec<_>>()
        );
    }
}
