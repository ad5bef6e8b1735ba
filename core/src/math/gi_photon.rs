//! PhotonGi's stored photon (Smal 2019, Table 24-2, derived in `docs/photon-gi.md`): what
//! `trace_indirect` writes and `splat_photons` reads, and where its precision goes.
//!
//! - power: rgb9e5 of `power / power_scale` ([`crate::math::packing::pack_rgb9e5`]): 9
//!   mantissa bits under the brightest channel's exponent, so each channel is within
//!   `2^-10` of the brightest channel's value (relative error up to `2^-10` on the
//!   brightest, more on a dim channel next to a bright one); `power_scale` is the frame's
//!   mean emitted photon power, which puts typical photons near `2^0` and keeps every
//!   photon within the format's `2^-24 .. 65408` range unless it is `2^24` times dimmer
//!   than the mean (those round to 0: counted as underflow);
//! - normal and direction: octahedral snorm16 x 2 (`pack_unit_vector`), within about
//!   `1e-4` rad;
//! - position and ray length: f32.

/// What `trace_indirect` stores ([`IndirectTraceParams::store`](crate::device::layout::IndirectTraceParams)).
pub mod gi_store {
    /// Packed 32-byte `GiPhoton`s (Table 24-2) for the splat.
    pub const PACKED: u32 = 0;
    /// Float `Photon`s (world position, flux in W, last segment, direction) for the
    /// reference deposit: the same photons without the packing.
    pub const FLOAT: u32 = 1;
}

/// Row-major index of the `tile_size`-pixel screen tile of pixel `(x, y)` in an image
/// `width` pixels wide.
#[inline]
pub fn screen_tile(x: u32, y: u32, width: u32, tile_size: u32) -> u32 {
    let tiles_x = width.div_ceil(tile_size.max(1));
    (y / tile_size.max(1)) * tiles_x + x / tile_size.max(1)
}

/// Screen tiles of a `width x height` image.
#[inline]
pub fn screen_tiles(width: u32, height: u32, tile_size: u32) -> u32 {
    width.div_ceil(tile_size.max(1)) * height.div_ceil(tile_size.max(1))
}
