//! The CPU kernels, one module per registry kernel, named as the kernel's declaration in
//! `caustica_core::kernels` (`prepare_scene` is [`crate::traversal::check_nodes`]: the
//! traversal reads the node buffer in place). What several kernels share lives in the
//! module of the kernel that defines it (`deposit_screen`'s photon-map deposit) or, for
//! the atlas deposit of `trace_photons` and `refine_clusters`, in
//! [`crate::atlas_deposit`].

pub mod atrous_filter;
pub mod bilateral_gather;
pub mod caustic_map_lookup;
pub mod composite;
pub mod density_gather;
pub mod deposit_screen;
pub mod direct_light;
pub mod gather_caustic_map;
pub mod gather_footprint;
pub mod photon_count_table;
pub mod primary_gbuffer;
pub mod refine_clusters;
pub mod resolve_caustics;
pub mod rsm_importance;
pub mod sample_rsm;
pub mod shading_normal_correction;
pub mod splat_photons;
pub mod temporal_blend;
pub mod tile_hit_distance;
pub mod trace_indirect;
pub mod trace_photons;

use caustica_core::device::layout::counter;
use caustica_core::math::fixed_point::join_u64;

/// Photon counters accumulated per worker and merged (sums are order-independent).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counters {
    /// Counts indexed like the device counter buffer ([`counter`]); a 64-bit counter sums
    /// in its first word and leaves the second unused.
    pub words: [u64; counter::WORDS],
}

impl Counters {
    /// Adds one to counter `word`.
    pub fn bump(&mut self, word: usize) {
        self.words[word] += 1;
    }

    /// The sum of two sets of counters.
    pub fn merge(mut self, o: Counters) -> Counters {
        for (a, b) in self.words.iter_mut().zip(o.words) {
            *a += b;
        }
        self
    }

    /// Adds to the device counter buffer: 32-bit counters wrap like the GPU atomics would
    /// (batches keep them far below 2^32), 64-bit (lo, hi) pairs carry.
    pub fn add_to(&self, buf: &mut [u32]) {
        let pairs = [
            counter::RAYS,
            counter::STORED_FLUX,
            counter::STORED_FLUX + 2,
            counter::STORED_FLUX + 4,
        ];
        for (i, &v) in self.words.iter().enumerate() {
            if pairs.contains(&i) {
                let sum = join_u64([buf[i], buf[i + 1]]).wrapping_add(v);
                buf[i] = sum as u32;
                buf[i + 1] = (sum >> 32) as u32;
            } else if !pairs.iter().any(|&p| i == p + 1) && i < buf.len() {
                buf[i] = buf[i].wrapping_add(v as u32);
            }
        }
    }
}
