//! Catalogue of stiff and extreme cases (docs/stability.md): each entry is a scene or input
//! with its expected behaviour stated, run on any backend by [`StiffCase::run`].
//!
//! Every case, on every backend, additionally checks ([`universal`]):
//! - no NaN or Inf in any output image (composite, raw and filtered caustics, direct);
//! - photon accounting: path ends add up to the photons emitted, deposit outcomes to the
//!   photons stored;
//! - stored flux never exceeds emitted flux, per channel (summed over the channels when a
//!   dispersive material gives a photon a colour: that rule holds per channel only in
//!   expectation, and a spectral photon's channel sum is at most the largest gain of a
//!   wavelength, `tolerance::spectral_sum_gain`), allowing the fixed-point rounding of half
//!   a quantum per stored photon;
//! - no fixed-point saturation;
//! - on a backend other than cpu: the frame agrees with the CPU backend's frame by
//!   [`compare_frames`], with the suite's tolerances as argued there.
//!
//! Conventions stated and tested here (see also `docs/stability.md`):
//! - **Relative IOR.** A dielectric's `ior` is relative to the medium *around the object*:
//!   glass (1.5) inside water (1.33) is an object of `ior = 1.5 / 1.33`. A kernel only ever
//!   sees one interface at a time, so nesting composes: `nested_glass_in_water` checks
//!   that a glass ball inside a water ball focuses where the closed form says.
//! - **Absorption in nested media.** Beer-Lambert is applied to a segment that ends on an
//!   *exiting* hit of a dielectric, with that dielectric's coefficient. A segment inside
//!   an outer absorbing medium that ends on *entering* an inner object is therefore not
//!   attenuated by the outer medium: nested absorbing media lose the outer medium's
//!   absorption over such segments (a documented limitation, not tested as correct).
//! - **Camera medium.** The camera is assumed to be in vacuum/air: a camera inside glass
//!   sees the glass's inner surface, which is not a receiver, so caustics behind it are
//!   not shown (direct light follows the specular chain through it).
//! - **Dynamic range.** The flux quantum is a power of two chosen per frame from the
//!   brightest photon (`2^24 <= max / quantum < 2^25`), so the absolute light intensity
//!   only has to fit f32 (tested at 1e-6 and 1e9 W/sr). Within one frame, a photon dimmer
//!   than `2^-25` of the brightest rounds to zero and is counted as underflow
//!   (`dynamic_range_mixed`); saturation cannot occur (the brightest photon is < 2^25
//!   units) and is checked to be zero everywhere.
//! - **Pixel footprint.** A pixel's radiance is `albedo / pi * Phi / A` with `A` its
//!   surface footprint (`core::footprint`), so `L * A * pi / albedo = Phi`: a pixel's
//!   contribution is bounded by the flux deposited in it, whatever its depth. The cases
//!   `near_plane` and `far_plane` check this bound and finiteness at footprints of
//!   ~1.5e-23 and ~5e8 scene units^2.
//!
//! One file per group of the catalogue (`optics.rs`, `screen.rs`, `scale.rs`, `range.rs`,
//! `degenerate.rs`, `termination.rs`), beside the shared machinery: `runner.rs` (the
//! universal checks and the comparison with the reference), `scenes.rs` (scene builders)
//! and `closed_form.rs` (bounds computed independently of the ray tracer).
//!
//! [`compare_frames`]: crate::techniques::sspm::compare_frames

mod adaptive_caustics;
mod caustic_map;
mod closed_form;
mod degenerate;
mod optics;
mod range;
mod runner;
mod scale;
mod scenes;
mod screen;
mod termination;

pub use degenerate::cheap_scene;
pub use runner::universal;
pub use scenes::transform_scene;

use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;

/// One stiff case: what it is, what must hold, and how to run it on a backend.
pub struct StiffCase {
    /// The catalogue's heading: optics, screen, scale, range, degenerate, termination.
    pub group: &'static str,
    pub name: &'static str,
    /// The expected behaviour, as the table prints it.
    pub expectation: &'static str,
    /// Renders the case on the backend (and the CPU reference where needed) and checks.
    pub run: fn(&mut dyn Backend) -> Result<Outcome, String>,
    /// Too heavy for lavapipe/PoCL within the test's time budget (8192^2 pixels, 2^26
    /// photons): the quirk table ([`crate::harness::quirks`]) holds it back on every
    /// backend but cpu unless asked (see `tests/stiff_cases.rs`).
    pub heavy: bool,
}

impl StiffCase {
    /// `group/name`: how the tests report the case and the quirk table names it.
    pub fn id(&self) -> String {
        format!("{}/{}", self.group, self.name)
    }
}

/// The result of a case on one backend: the key measured number and the verdict.
pub struct Outcome {
    pub key: String,
    pub verdict: Verdict,
}

/// Image size of the small cases: `width - height` odd, for the reason given at
/// [`BUILTIN_SIZE`](crate::harness::cases::BUILTIN_SIZE).
pub const SIZE: (u32, u32) = (64, 37);

/// Photon grid of the small cases (per light).
pub const GRID: u32 = 128;

/// The catalogue, in table order.
pub fn catalogue() -> Vec<StiffCase> {
    macro_rules! case {
        ($group:expr, $name:expr, $f:path, $exp:expr) => {
            StiffCase {
                group: $group,
                name: $name,
                expectation: $exp,
                run: $f,
                heavy: false,
            }
        };
    }
    let mut v = vec![
        case!("optics", "tir-critical", optics::tir_critical,
            "Prism lit so that the exit face is met exactly at the critical angle: Fresnel is continuous into TIR (R -> 1), no NaN; stored <= emitted"),
        case!("optics", "light-inside-glass-tir", optics::light_inside_glass,
            "Point light at the centre of a glass cube (n 1.5): directions with every |cosine| < sqrt(1 - 1/n^2) are trapped by TIR; the fraction at the bounce limit >= 1 - 3 (1 - sqrt(1 - 1/n^2)) = 0.236 (minus the grid bound)"),
        case!("optics", "grazing", optics::grazing,
            "Sun at cos 1e-3 onto a glass slab: Fresnel -> 1, at most (1 - F(1e-3)) = 0.58% of the photons enter, stored <= (1 - F) N + 5 sigma"),
        case!("optics", "ior-1", optics::ior_one,
            "Ball of IOR exactly 1 vanishes: no reflection (no photon lost), stored flux = I * Omega_ball (grid bound); direct light on lit pixels bitwise equal to the scene without the ball (its shadow is filled by the caustic)"),
        case!("optics", "far-light", optics::far_light,
            "ior-1's vanishing ball under a point light 2e4 radii above it (caster cone 5e-5 rad, its cosine 1 in f32): stored flux = I * Omega_ball (grid bound), every floor pixel within 0.8 radii of the beam's axis lit and none beyond 1.2"),
        case!("optics", "narrow-spot", optics::narrow_spot,
            "far-light's set-up under a spot of 0.02 degrees 1000 radii away (its cosines 1 and 1 - 2^-24 in f32) aimed at the ball: emitted I * Omega_spot, stored I * Omega_spot / 2 (the smoothstep falloff's mean over the cone) within 1e-3"),
        case!("optics", "distant-spot", optics::distant_spot,
            "narrow-spot's set-up from 1e4 and 1e5 units, the cone 0.7 radii wide at the ball (sideways direction components below 2^-23): no photon passes the ball, stored I * Omega_spot / 2 within 1e-3"),
        case!("optics", "ior-below-1", optics::ior_below_one,
            "Air bubble (ior 1/1.33) inside a water ball: TIR on entering the bubble, no NaN, stored <= emitted"),
        case!("optics", "ior-4", optics::ior_four,
            "Ball of IOR 4 (focus inside the ball, R0 = 0.36): no NaN, stored <= emitted"),
        case!("optics", "nested-glass-in-water", optics::nested_glass_in_water,
            "Glass ball (ior 1.5/1.33 relative) inside a water ball, thin axial sun beam: >= 99% of the deposited caustic, and of the filtered one, in the 3x3 pixels at the closed-form paraxial focus"),
        case!("optics", "absorption-0", optics::absorption_zero,
            "Absorption 0 per unit: stored flux >= (1 - F)^2 averaged over the ball's disk times I * Omega_ball (grid bound): nothing absorbed"),
        case!("optics", "absorption-1e6", optics::absorption_huge,
            "Absorption 1e6 per unit: every photon through the ball is absorbed (exp underflows to 0, no NaN); stored flux <= mean Fresnel reflectance times I * Omega_ball + grid bound"),
        case!("optics", "dispersion-b0", optics::dispersion_zero,
            "Cauchy B = 0: the material is not dispersive, photons keep all three channels: white light gives bitwise equal stored flux per channel"),
        case!("optics", "dispersion-strong", optics::dispersion_strong,
            "Cauchy B = 0.3 um^2 (n 1.51..2.59 over 380-780 nm): no NaN, channel-summed stored flux <= emitted x the largest gain of a wavelength; B = 2 (n < 0 in red) rejected by validation"),
        case!("optics", "dispersion-abbe-near-1", optics::dispersion_abbe_near_one,
            "Abbe model n_d 1.0001, V_d 0.5: the index falls to the extension's clamp at 1 from 689 nm on (checked), photons at both ends of the spectrum; no NaN"),
        case!("optics", "dispersion-abbe-3.5", optics::dispersion_abbe_high_index,
            "Abbe model n_d 3.5, V_d 10 (n 3.34..4.03, total internal reflection nearly everywhere inside): no NaN; V_d 0, < 0, NaN, 1e-30 (index overflow), B with the Abbe model and n_d < 1 rejected naming the field"),
        case!("screen", "near-plane", screen::near_plane,
            "sphere scene at 1e-9 scale seen from 3e-10 above the caustic (pixel footprint ~1.5e-23 units^2): radiance finite, each pixel's flux L * A * pi / albedo <= stored flux"),
        case!("screen", "far-plane", screen::far_plane,
            "Camera 1e6 away (pixel footprint ~1e8 units^2): finite, per-pixel flux bounded by the stored flux"),
        case!("screen", "camera-inside-glass", screen::camera_inside_glass,
            "Camera inside the glass ball: the G-buffer sees the ball's inner surface (not a receiver: no caustic deposited), direct light follows the chain; no NaN"),
        case!("scale", "scale-1e-4", scale::scale_small,
            "sphere scene x 1e-4 (intensity x 1e-8): caustics match the unscaled ones within compare_frames' image bound sqrt(2k/n) + 1e-4; the filter keeps the focus (filtered peak >= 0.9 of the raw peak: no radius in scene units)"),
        case!("scale", "scale-1e5", scale::scale_large,
            "sphere scene x 1e5 (intensity x 1e10): caustics match the unscaled ones within sqrt(2k/n) + 1e-4; filtered peak >= 0.9 of the raw peak"),
        case!("scale", "instance-scale-1e-4", scale::instance_scale_small,
            "sphere scene x 1e-4 with the ball an instance (its unscaled object-space ball placed by a transform of scale 1e-4): caustics match the unscaled static scene within sqrt(2k/n) + 1e-4; filtered peak >= 0.9 of the raw peak"),
        case!("scale", "instance-scale-1e5", scale::instance_scale_large,
            "sphere scene x 1e5 with the ball an instance (transform scale 1e5): caustics match the unscaled static scene within sqrt(2k/n) + 1e-4; filtered peak >= 0.9 of the raw peak"),
        case!("scale", "offset-1e6", scale::offset_far,
            "sphere scene x 1e3 offset by (1e6, 1e6, 1e6) (f32 grid 0.0625 = 1.6e-5 of the scene): caustics match the unscaled ones within the image bound with the divergence allowance widened x16 for that grid (argued in the code); a unit-size scene at 1e6 is below f32 resolution; filtered peak >= 0.9 of the raw peak"),
        case!("range", "intensity-1e-6", range::intensity_tiny,
            "Light 1e-6 W/sr: saturated = underflow = 0; raw caustics x 1e7 equal those at 10 W/sr within RESOLVE_REL"),
        case!("range", "intensity-1e9", range::intensity_huge,
            "Light 1e9 W/sr: saturated = underflow = 0; raw caustics x 1e-8 equal those at 10 W/sr within RESOLVE_REL"),
        case!("range", "mixed-1e-6-and-1e9", range::dynamic_range_mixed,
            "Two lights 1e-6 and 1e9 W/sr in one frame (ratio 1e15 > 2^25): the dim light's photons underflow and are counted (underflow > 0), saturated = 0"),
        case!("degenerate", "zero-area-and-repeated-vertices", degenerate::degenerate_triangles,
            "Mesh with zero-area triangles and repeated vertices: accepted (degenerate triangles never hit), frame agrees with the clean mesh's"),
        case!("degenerate", "nan-normals", degenerate::nan_normals,
            "NaN or zero vertex normals / NaN positions in input: rejected with an error naming the field (objects[i].shape.normals[k])"),
        case!("degenerate", "zero-size-lights", degenerate::zero_size_lights,
            "Directional light with a point-sized projection volume, spot of 1e-4 deg, zero-power point: no NaN, nothing stored from zero flux, the flat volume's and the zero-power light skipped with their reasons in the plan"),
        case!("degenerate", "image-1x1", degenerate::image_1x1,
            "1x1 image: finite, bounded, agrees with cpu"),
        case!("degenerate", "photons-1", degenerate::photons_1,
            "1 photon per light: emitted 1, finite, bounded"),
        case!("termination", "facing-mirrors", termination::facing_mirrors,
            "Two facing mirrors of reflectance 1: paths end at the bounce limit (bounce_limit > 0), stored <= emitted"),
        case!("caustic-map", "atlas-1x1", caustic_map::atlas_1x1,
            "CausticMap with a 1x1 atlas (one texel for the floor): finite, accounted, agrees with cpu"),
        case!("caustic-map", "atlas-16384", caustic_map::atlas_16384,
            "CausticMap with a 16384^2 atlas (36 GiB with the density gather) under the default max_atlas_bytes (4 GiB): a typed OutOfMemory naming the setting, before any work"),
        case!("caustic-map", "grazing-receiver", caustic_map::grazing_receiver,
            "Sun 2 degrees above the floor through the ball: finite, accounted, stored <= emitted, agrees with cpu"),
        case!("caustic-map", "tiny-receiver", caustic_map::tiny_receiver,
            "A 1e-6 units^2 receiver beside the floor (texels of near-zero world area): finite, accounted, agrees with cpu"),
        case!("caustic-map", "uv-seams", caustic_map::uv_seams,
            "A box receiver (six UV islands, seams between them): the 3x3 box gather, the raw map and the density gather keep the stored flux (sum of irradiance x texel area) within 1e-5, 1e-5 and 1e-4; agrees with cpu"),
        case!("caustic-map", "generated-uv-charts", caustic_map::generated_uv_charts,
            "A receiver mesh without UVs (a box of 8 shared corners): refused by name, pointing at scene::uv_charts; with generated charts (six, with gutters) the 3x3 box gather keeps the stored flux within 1e-5 and the density gather within 1e-4 (flux in uncovered border texels goes to a covered neighbour of the chart); the raw map shows all but the uncovered texels' flux (below 1%); agrees with cpu"),
        case!("caustic-map", "overlapping-uvs", caustic_map::overlapping_uvs,
            "A receiver mesh whose triangles share UVs: a typed InvalidScene naming the object and the overlap"),
        case!("caustic-map", "dispersion-split", caustic_map::dispersion_split,
            "The dispersive prism with Vanderstichelen 2021's deterministic splits and with the stochastic choice: accounted (path ends = emitted + splits), both agree with cpu, and they store the same flux per channel within 3%"),
        case!("caustic-map", "ior-extremes", caustic_map::ball_glass,
            "Ball of IOR 1.0001 and 4 over the floor: finite, accounted, agrees with cpu"),
        case!("caustic-map", "schlick", caustic_map::schlick,
            "Vanderstichelen 2021's Schlick reflectance on sphere, split and stochastic: finite, accounted, agrees with cpu; the split's stored flux over the exact model's is the closed forms' ratio 1.0150 within 0.3%"),
        case!("adaptive-caustics", "small-caster", adaptive_caustics::small_caster,
            "A glass bead a tenth of a start-grid cluster across under spot-glass's light, plane over the whole cone: with the casters' projected bounds (the default relevance) the level metric stores bitwise the dense grid's photons, and the screen target the same photons; Wyman 2009's photon test loses the bead's caustic (stated, checked: stored flux below the dense grid's)"),
        case!("adaptive-caustics", "grazing-caster", adaptive_caustics::grazing_caster,
            "Sun 3 degrees above a thin glass slab (R = 0.83): photons stored on the far floor, finite, accounted, agrees with cpu; the level metric equals the dense grid bitwise, the screen target receives the same photons"),
        case!("adaptive-caustics", "light-inside-casters", adaptive_caustics::light_inside_casters,
            "Point light between two glass balls (six cube faces, each its own pyramid rounded to 256^2): finite, accounted, agrees with cpu; equals the dense grid of 256^2 faces bitwise, the screen target receives the same photons"),
        case!("adaptive-caustics", "far-from-origin", adaptive_caustics::far_from_origin,
            "A glass cube under a sun, the scene moved by 1e4 (f32 resolves 1e-3 there), the plane over the whole footprint: the casters' rectangles, padded by that rounding, hold every cluster whose photons meet the cube, so the seeded level metric stores bitwise the dense grid's photons; finite, accounted, agrees with cpu"),
    ];
    v.push(StiffCase {
        group: "degenerate",
        name: "image-8192x8192",
        expectation: "8192x8192 image of a cheap scene: finite, bounded; the G-buffer in planes of 16 B/px (1 GiB each) renders where that fits (NVIDIA Vulkan and wgpu: 2^32 - 1 bytes); where the device binds less (lavapipe: 128 MiB), Sspm::new returns OutOfMemory naming the G-buffer plane",
        run: degenerate::image_8192,
        heavy: true,
    });
    v.push(StiffCase {
        group: "degenerate",
        name: "photons-2^26",
        expectation: "2^26 photons in 64 batches of 2^20 (photon buffer 32 MiB): photons_emitted = 2^26, path ends add up, stored flux bitwise equal to a 4-batch run",
        run: degenerate::photons_2_26,
        heavy: true,
    });
    v
}
