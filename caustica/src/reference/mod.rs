//! Reference images for error measurement: the converged answer of a technique's
//! estimator (by default Sspm's, whose path class, light -> specular -> diffuse receiver,
//! the caustic techniques share), i.e. the progressive mean of its *unfiltered* estimate
//! (for Sspm the raw screen-space photon deposit) over frames with different seeds, computed on the CPU backend until the
//! relative standard error of the mean over the caustic pixels falls below a stated noise
//! level (or a frame cap is hit, which the reference records). Cached on disk as EXR with
//! a JSON sidecar (photon count, frames, reached noise, scene hash) and recomputed when the
//! scene, the image size or the reference settings change.

pub mod light_tracer;

pub(crate) use crate::output::read_exr;
use caustica_core::frame::image::{luminance, Image};
use caustica_core::frame::metrics::{CausticMask, MASK_FRACTION};
use caustica_core::techniques::create;
use caustica_core::{Backend, Scene};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// How a reference is computed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceSpec {
    /// The technique whose unfiltered estimate converges to the reference: a registry
    /// name, or a technique spec with settings (`technique_spec::technique_spec`; PhotonGi's
    /// indirect reference is [`INDIRECT_REFERENCE`]).
    #[serde(default = "default_technique")]
    pub technique: String,
    /// Image size (pixels).
    pub width: u32,
    /// Image size (pixels).
    pub height: u32,
    /// Photon grid side per light and frame.
    pub photons_side: u32,
    /// Stop when the relative standard error of the mean (RMS over the caustic pixels,
    /// relative to the RMS of the mean) is at most this.
    pub target_noise: f64,
    /// Stop after this many frames whatever the noise (recorded in the sidecar).
    pub max_frames: u32,
}

/// The technique spec of the indirect-light reference: PhotonGi's raw deposit
/// of every photon hit after the first bounce (`estimator: deposit`: no splat, no filter),
/// the quantity its splats estimate.
pub const INDIRECT_REFERENCE: &str =
    "photon-gi:estimator=deposit+temporal=false+atrous_iterations=0";

/// The reference technique `technique` (a registry name) is measured against: the
/// indirect reference for PhotonGi, `spec`'s (the caustic reference by default)
/// otherwise.
pub fn reference_for(technique: &str, spec: &ReferenceSpec) -> ReferenceSpec {
    if technique == "photon-gi" {
        ReferenceSpec {
            technique: INDIRECT_REFERENCE.into(),
            ..spec.clone()
        }
    } else {
        spec.clone()
    }
}

/// Whether the independent light tracer ([`light_tracer`]) estimates the light
/// `technique` (a registry name) estimates: the caustic techniques' paths (light, one or
/// more specular events, a diffuse receiver) for `sspm`, `caustic-map` and
/// `adaptive-caustics`; not PhotonGi's indirect light (every path after the first diffuse
/// bounce), whose only reference is its own converged deposit ([`INDIRECT_REFERENCE`]).
pub fn traced_by_light_tracer(technique: &str) -> bool {
    matches!(technique, "sspm" | "caustic-map" | "adaptive-caustics")
}

/// The technique spec of the caustic reference: Sspm's raw deposit with the tangent-plane
/// store test (`depth_tolerance < 0`), which keeps every photon on the surface a pixel's
/// centre sees; Kim 2019's view-depth test drops photons of surfaces seen at a grazing
/// angle in coarse images (half of `rooms`' at 160x90), so a reference made with it
/// converged to less than the pixel-averaged irradiance there.
pub const CAUSTIC_REFERENCE: &str = "sspm:depth_tolerance=-0.01";

fn default_technique() -> String {
    CAUSTIC_REFERENCE.into()
}

impl Default for ReferenceSpec {
    fn default() -> Self {
        ReferenceSpec {
            technique: default_technique(),
            width: 480,
            height: 270,
            photons_side: 1024,
            target_noise: 0.02,
            max_frames: 256,
        }
    }
}

/// A reference image and how it was made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceInfo {
    /// Scene name.
    pub scene: String,
    /// [`scene_hash`] of the inputs: the cache key.
    pub scene_hash: String,
    /// How it was computed.
    pub spec: ReferenceSpec,
    /// Photons emitted over all frames.
    pub photons: u64,
    /// Frames averaged.
    pub frames: u32,
    /// Relative standard error reached; NaN (`null` in the sidecar) for a reference in
    /// which no pixel carries signal ([`holds_signal`]): an empty image has no relative
    /// error, it is not an exact one.
    #[serde(deserialize_with = "nan_for_null")]
    pub noise: f64,
}

/// Reads a number, or `null` as NaN: serde_json writes a NaN (an empty reference's
/// noise) as `null`, and the sidecar must read back what it wrote.
fn nan_for_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// Whether any pixel of `image` carries signal: the caustic mask
/// ([`caustica_core::frame::metrics::CausticMask`]) of an image with no positive
/// luminance is empty, and errors measured against it would be 0/0.
pub fn holds_signal(image: &Image) -> bool {
    CausticMask::from_reference(image).count > 0
}

/// A converged reference: the mean image (linear radiance) and how it was made.
pub struct Reference {
    /// Mean of the unfiltered estimate over the frames (W/(sr m^2) per channel).
    pub image: Image,
    /// How it was made.
    pub info: ReferenceInfo,
}

/// FNV-1a (64 bit) of the scene file text, the image size and the reference settings: a
/// reference is reused only for exactly the same inputs.
pub fn scene_hash(scene: &Scene, spec: &ReferenceSpec) -> String {
    let text = format!(
        "{}|{}x{}|{}|{}|{}|seeds from {REFERENCE_FIRST_SEED}",
        caustica_core::scene::format::to_json(scene),
        spec.width,
        spec.height,
        spec.photons_side,
        spec.target_noise,
        spec.max_frames
    );
    // Another technique's estimate is another reference (Sspm's keeps its old key).
    let text = if spec.technique == "sspm" {
        text
    } else {
        format!("{text}|{}", spec.technique)
    };
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// The sidecar of the cached image `exr` beside it at `json`, where both are there, the
/// sidecar reads and `hash_of` it is `hash`; `None` where the cache lacks it (or holds
/// another scene's under the name).
pub(crate) fn cached_sidecar<T: serde::de::DeserializeOwned>(
    exr: &Path,
    json: &Path,
    hash: &str,
    hash_of: impl Fn(&T) -> &str,
) -> Option<T> {
    let text = std::fs::read_to_string(json).ok()?;
    let info = serde_json::from_str::<T>(&text).ok()?;
    (exr.exists() && hash_of(&info) == hash).then_some(info)
}

/// The file name of the reference of `scene` under `spec` where `dir` lacks it; `None`
/// where [`load_or_compute`] would load it.
pub fn missing_from_cache(dir: &Path, scene: &Scene, spec: &ReferenceSpec) -> Option<String> {
    let hash = scene_hash(scene, spec);
    let (exr, json) = paths(dir, &scene.name, &hash);
    match cached_sidecar::<ReferenceInfo>(&exr, &json, &hash, |i| &i.scene_hash) {
        Some(_) => None,
        None => Some(file_name(&exr)),
    }
}

/// `path`'s last component, for messages.
pub(crate) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

fn paths(dir: &Path, scene: &str, hash: &str) -> (PathBuf, PathBuf) {
    let stem = format!("{}-{hash}", crate::output::file_stem(scene));
    (
        dir.join(format!("{stem}.exr")),
        dir.join(format!("{stem}.json")),
    )
}

/// Loads the cached reference of `scene`, or computes it on `backend` (the CPU backend
/// by convention) and caches it; `progress(frames_done, max_frames, noise)` after each
/// frame.
pub fn load_or_compute(
    dir: &Path,
    scene: &Scene,
    spec: &ReferenceSpec,
    backend: &mut dyn Backend,
    progress: &mut dyn FnMut(u32, u32, f64),
) -> Result<Reference, String> {
    let hash = scene_hash(scene, spec);
    let (exr_path, json_path) = paths(dir, &scene.name, &hash);
    if let Some(info) =
        cached_sidecar::<ReferenceInfo>(&exr_path, &json_path, &hash, |i| &i.scene_hash)
    {
        return Ok(Reference {
            image: read_exr(&exr_path)?,
            info,
        });
    }
    // the cache must take the result before the work begins
    crate::output::prepare_folder(dir).map_err(|e| format!("reference cache {e}"))?;
    let r = compute(scene, spec, backend, progress, hash)?;
    crate::output::write_exr(&exr_path, &r.image)?;
    let text = serde_json::to_string_pretty(&r.info).map_err(|e| e.to_string())?;
    crate::output::write_file(&json_path, text.as_bytes())?;
    Ok(r)
}

/// The seed of a reference's first frame: its frames take seeds from here on, far from
/// the seeds 1, 2, ... that the frames measured against it take (`caustica report`'s
/// repeats), so that no measured frame is part of its own reference.
pub const REFERENCE_FIRST_SEED: u32 = 1 << 20;

/// Progressive mean of the raw caustics over frames with seeds
/// [`REFERENCE_FIRST_SEED`], `REFERENCE_FIRST_SEED + 1`, ...; `scene_hash` is recorded
/// in the reference's info. `spec.max_frames` must be at least 2 (the noise is the
/// spread of the frames). `progress(frames_done, max_frames, noise)` after each frame,
/// the noise NaN while it is undefined (after one frame, or while no pixel carries
/// signal). An image still empty after 4 frames holds no caustic and stops there, its
/// noise NaN ([`ReferenceInfo::noise`]).
pub fn compute(
    scene: &Scene,
    spec: &ReferenceSpec,
    backend: &mut dyn Backend,
    progress: &mut dyn FnMut(u32, u32, f64),
    scene_hash: String,
) -> Result<Reference, String> {
    if spec.max_frames < 2 {
        return Err(format!(
            "a reference needs at least 2 frames, its noise being their spread (max_frames \
             is {})",
            spec.max_frames
        ));
    }
    let mut scene = scene.clone();
    scene.camera.width = spec.width;
    scene.camera.height = spec.height;
    let (name, settings) = reference_settings(spec)?;
    let mut sspm = create(name, backend, &scene, &settings).map_err(|e| e.to_string())?;
    let (_, raw_output) = sspm.estimate_outputs();
    let n = (spec.width * spec.height) as usize;
    let mut sum = vec![[0.0f64; 3]; n];
    let mut sum2 = vec![[0.0f64; 3]; n];
    let (mut frames, mut photons, mut noise) = (0u32, 0u64, None);
    while frames < spec.max_frames {
        sspm.set_seed(REFERENCE_FIRST_SEED + frames);
        let stats = sspm
            .frame(backend, &mut |_| {})
            .map_err(|e| e.to_string())?;
        photons += stats.photons_emitted;
        let raw = sspm
            .read_output(backend, raw_output)
            .map_err(|e| e.to_string())?;
        for (i, p) in raw.pixels.iter().enumerate() {
            for c in 0..3 {
                let v = p[c] as f64;
                sum[i][c] += v;
                sum2[i][c] += v * v;
            }
        }
        frames += 1;
        noise = relative_noise(&sum, &sum2, frames);
        progress(frames, spec.max_frames, noise.unwrap_or(f64::NAN));
        // an image still empty after 4 frames holds no caustic: more would not change it
        if frames >= 4 && noise.is_none_or(|n| n <= spec.target_noise) {
            break;
        }
    }
    sspm.free(backend).map_err(|e| e.to_string())?;
    let k = frames as f64;
    let pixels = sum
        .iter()
        .map(|s| [(s[0] / k) as f32, (s[1] / k) as f32, (s[2] / k) as f32, 1.0])
        .collect();
    Ok(Reference {
        image: Image::new(spec.width, spec.height, pixels),
        info: ReferenceInfo {
            scene: scene.name.clone(),
            scene_hash,
            spec: spec.clone(),
            photons,
            frames,
            noise: noise.unwrap_or(f64::NAN),
        },
    })
}

/// [`relative_noise`] as one number, as the light tracer records it: infinite before 2
/// samples, 0 where no pixel carries signal (tell an empty image by [`holds_signal`],
/// not by this 0).
fn relative_standard_error(sum: &[[f64; 3]], sum2: &[[f64; 3]], k: u32) -> f64 {
    match relative_noise(sum, sum2, k) {
        Some(n) => n,
        None if k < 2 => f64::INFINITY,
        None => 0.0,
    }
}

/// The technique (a registry name) whose frames make the reference `spec`, and the
/// settings they run with, a JSON object: `spec.technique` may be a spec with settings
/// (`photon-gi:estimator=deposit+...`), laid over the photon grid of `spec.photons_side`.
pub fn reference_settings(spec: &ReferenceSpec) -> Result<(&str, serde_json::Value), String> {
    let (name, overrides) = crate::technique_spec::technique_spec(&spec.technique)?;
    let mut settings = serde_json::Map::new();
    crate::technique_spec::put_setting(&mut settings, "frame.photons_w", spec.photons_side.into());
    crate::technique_spec::put_setting(&mut settings, "frame.photons_h", spec.photons_side.into());
    crate::technique_spec::merge_settings(&mut settings, overrides);
    Ok((name, serde_json::Value::Object(settings)))
}

/// RMS standard error of the per-pixel means over the caustic pixels (mask from the
/// current mean, as metrics::CausticMask), relative to the RMS of the means, from `k`
/// samples' per-pixel sums and sums of squares; `None` where it is undefined: fewer than
/// 2 samples, or no pixel carries signal.
fn relative_noise(sum: &[[f64; 3]], sum2: &[[f64; 3]], k: u32) -> Option<f64> {
    if k < 2 {
        return None;
    }
    let k = k as f64;
    let lum: Vec<f64> = sum
        .iter()
        .map(|s| luminance([(s[0] / k) as f32, (s[1] / k) as f32, (s[2] / k) as f32]) as f64)
        .collect();
    let max = lum.iter().copied().fold(0.0f64, f64::max);
    let (mut var, mut sq) = (0.0f64, 0.0f64);
    for (i, (s, s2)) in sum.iter().zip(sum2).enumerate() {
        if !(max > 0.0 && lum[i] > MASK_FRACTION as f64 * max) {
            continue;
        }
        for c in 0..3 {
            let mean = s[c] / k;
            let sample_var = ((s2[c] / k - mean * mean) * k / (k - 1.0)).max(0.0);
            var += sample_var / k; // variance of the mean
            sq += mean * mean;
        }
    }
    (sq > 0.0).then(|| (var / sq).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_image_has_no_noise_not_a_zero_one() {
        let (sum, sum2) = (vec![[0.0; 3]; 4], vec![[0.0; 3]; 4]);
        assert_eq!(relative_noise(&sum, &sum2, 4), None);
        assert_eq!(relative_noise(&[[1.0; 3]], &[[1.0; 3]], 1), None);
        // two samples 1 and 3 of one pixel: mean 2, sample variance 2, of the mean 1
        let n = relative_noise(&[[4.0; 3]], &[[10.0; 3]], 2).expect("defined");
        assert!((n - 0.5).abs() < 1e-12, "{n}");
        // the light tracer's number: 0 for an image without signal
        assert_eq!(relative_standard_error(&sum, &sum2, 4), 0.0);
        assert!(!holds_signal(&Image::new(2, 2, vec![[0.0; 4]; 4])));
    }

    #[test]
    fn an_empty_reference_reads_back_from_its_sidecar() {
        let info = ReferenceInfo {
            scene: "plain".into(),
            scene_hash: "0".into(),
            spec: ReferenceSpec::default(),
            photons: 0,
            frames: 4,
            noise: f64::NAN,
        };
        let text = serde_json::to_string(&info).expect("serialises");
        assert!(text.contains("\"noise\":null"), "{text}");
        let back: ReferenceInfo = serde_json::from_str(&text).expect("reads back");
        assert!(back.noise.is_nan());
    }
}
