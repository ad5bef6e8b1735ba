//! The sort key of PhotonGi's queued indirect paths (the `sorted_waves` schedule): the
//! octant of the path's direction, then a coarse Morton code of its origin in the scene's
//! box, so that a warp of the next wave takes paths that leave one region in one general
//! direction and so walk similar parts of the BVH (a cheap coherence key in the spirit of
//! the ray-reordering literature, e.g. Meister, Boksansky, Guthe and Bittner 2025).

use glam::Vec3;

/// Morton bits per axis of the origin's cell (`2^3` cells a side).
pub const PATH_SORT_BITS: u32 = 3;

/// Buckets of the key: 8 direction octants times `2^(3 PATH_SORT_BITS)` origin cells.
pub const PATH_SORT_BUCKETS: u32 = 8 << (3 * PATH_SORT_BITS);

/// The launches of `sort_indirect_paths` (`PathSortParams::phase`); the buckets' counts
/// come from the wave that queued the paths (`trace_indirect`'s `queue_keys`).
pub mod path_sort_phase {
    /// One workgroup turns the bucket counts into their first slots (exclusive sums).
    pub const SCAN: u32 = 0;
    /// Each path's queue slot is written at its bucket's first slot plus its rank there.
    pub const SCATTER: u32 = 1;
}

/// A queued path's sort key and its rank among the queue's paths of that key
/// (`trace_indirect`'s `path_keys`, one per queue slot).
pub type PathKey = [u32; 2];

/// The key of a path at `origin` going `direction`: octant (bit 0 x, 1 y, 2 z set where
/// that component is negative) above the Morton code (x in bit `3b`, y `3b + 1`, z
/// `3b + 2`) of the cell `clamp(floor((origin - origin_min) x origin_scale), 0,
/// 2^PATH_SORT_BITS - 1)` per axis (`origin_scale`: cells per scene unit). Exact on
/// every port: one subtraction and one product per axis, which no port contracts.
#[inline]
pub fn path_sort_key(origin: Vec3, direction: Vec3, origin_min: Vec3, origin_scale: Vec3) -> u32 {
    let top = ((1u32 << PATH_SORT_BITS) - 1) as f32;
    let cell = |o: f32, lo: f32, s: f32| ((o - lo) * s).max(0.0).min(top) as u32;
    let (x, y, z) = (
        cell(origin.x, origin_min.x, origin_scale.x),
        cell(origin.y, origin_min.y, origin_scale.y),
        cell(origin.z, origin_min.z, origin_scale.z),
    );
    let mut morton = 0u32;
    for b in 0..PATH_SORT_BITS {
        morton |= ((x >> b) & 1) << (3 * b)
            | ((y >> b) & 1) << (3 * b + 1)
            | ((z >> b) & 1) << (3 * b + 2);
    }
    let octant = (direction.x < 0.0) as u32
        | ((direction.y < 0.0) as u32) << 1
        | ((direction.z < 0.0) as u32) << 2;
    octant << (3 * PATH_SORT_BITS) | morton
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_split_octants_then_cells() {
        let (lo, s) = (Vec3::ZERO, Vec3::splat(8.0));
        assert_eq!(path_sort_key(Vec3::ZERO, Vec3::ONE, lo, s), 0);
        // the far corner: every Morton bit
        let far = path_sort_key(Vec3::ONE, Vec3::ONE, lo, s);
        assert_eq!(far, (1 << (3 * PATH_SORT_BITS)) - 1);
        // outside the box clamps to the edge cells
        assert_eq!(path_sort_key(Vec3::splat(-5.0), Vec3::ONE, lo, s), 0);
        assert_eq!(path_sort_key(Vec3::splat(9.0), Vec3::ONE, lo, s), far);
        // -x direction: octant 1
        let k = path_sort_key(Vec3::ZERO, Vec3::new(-1.0, 0.0, 0.0), lo, s);
        assert_eq!(k, 1 << (3 * PATH_SORT_BITS));
        assert!(path_sort_key(Vec3::ONE, -Vec3::ONE, lo, s) < PATH_SORT_BUCKETS);
    }
}
