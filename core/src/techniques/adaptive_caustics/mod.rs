//! AdaptiveCaustics (seed 004, Wyman and Nichols, "Adaptive Caustic Maps Using Deferred
//! Shading"): CausticMap's light view planes sampled coarse to fine, so that photons are
//! traced only where the casters are and, with the error metric, only where the caustic
//! map still needs them. Everything after the photons is CausticMap's: the same atlas,
//! gather, final pass and outputs (`caustic_map`), so the two differ only in which
//! photons reach the map.
//!
//! The source emits photons by point-sampling rasterised G-buffers of the refractor from
//! the light and refracts them in image space; here the traversal drives the exact
//! tracer of the other techniques (`trace_photons`, its `ADAPTIVE` variant), which makes
//! the source's G-buffer resolution question moot.
//!
//! Per frame with photon work, per light view plane (`traversal`): the 64^2 start grid's
//! 2x2 clusters are traced and judged (`refine_clusters`): discarded when every photon
//! missed the casters, output (deposited into the atlas) at the finest level or when the
//! error metric holds, else refined into four clusters of the next level; batches of
//! clusters under `max_traversal_bytes`. Photons output early carry their coarse texels'
//! flux (the cluster's solid angle or area), so the map's expectation is the dense
//! grid's. With 004's one-texel metric (`error_texels: 1`) they all landed in one atlas
//! texel, so that texel *is* the cluster's footprint; with a wider tolerance (004's
//! alternative) each output photon is splatted over its cluster's footprint, the flux
//! split exactly (`math::photon_clusters::footprint_window`).
//!
//! The deposit target is a setting (`deposit`): CausticMap's atlas (the default) or Sspm's
//! screen ([`AdaptiveCaustics::build_screen`]: Sspm's frame whose photons are the
//! traversal's, listed in world space by `refine_clusters` and deposited by
//! `deposit_screen`; a photon's "texel" for the error metric is then its pixel).

mod screen;
mod settings;

pub use crate::frame::emission::adaptive::{
    caster_rects, fit_planes, AtlasTarget, DepositTarget, PhotonOptics, ScreenTarget, Traversal,
    TraversalSettings, EMPTY_RECT,
};
pub use screen::AdaptiveScreen;
pub use settings::{
    AdaptiveCausticsSettings, AdaptiveDeposit, AdaptiveMetric, ClusterRelevance,
    LIST_BYTES_PER_CLUSTER, SLOT_BYTES_PER_CLUSTER,
};

use crate::backend::Backend;
use crate::frame::error::Error;
use crate::frame::technique::Technique;
use crate::scene::Scene;
use crate::techniques::caustic_map::CausticMap;

/// The traversal a [`CausticMap`] runs instead of its dense planes.
#[derive(Clone, Debug)]
pub(crate) struct AdaptiveSetup {
    /// The traversal's settings (its `map` field unused: the technique's own settings
    /// hold the map's).
    pub settings: AdaptiveCausticsSettings,
    /// Its device buffers, made with the atlas.
    pub traversal: Option<Traversal>,
    /// Bounding box of each caster object (world space).
    pub caster_boxes: Vec<crate::math::geometry::Aabb>,
    /// The scene object of each box (they follow moved instances).
    pub caster_objects: Vec<u32>,
}

/// The bounding box of every caster object (mirror or dielectric) of `ds`, from its
/// triangles, in object order.
pub fn caster_boxes(
    ds: &crate::device::device_scene::DeviceScene,
) -> Vec<crate::math::geometry::Aabb> {
    caster_boxes_by_object(ds)
        .into_iter()
        .map(|(_, b)| b)
        .collect()
}

/// [`caster_boxes`] with the scene object each box belongs to.
pub fn caster_boxes_by_object(
    ds: &crate::device::device_scene::DeviceScene,
) -> Vec<(u32, crate::math::geometry::Aabb)> {
    use crate::device::layout::material_kind;
    use crate::math::geometry::Aabb;
    let mut boxes: std::collections::BTreeMap<u32, Aabb> = Default::default();
    for (t, obj) in ds.triangles.iter().zip(&ds.triangle_objects) {
        if ds.materials[t.material as usize].kind == material_kind::DIFFUSE {
            continue;
        }
        let b = boxes.entry(*obj).or_insert(Aabb::EMPTY);
        for i in t.indices {
            b.grow(glam::Vec3::from(ds.vertices[i as usize].position));
        }
    }
    boxes.into_iter().collect()
}

/// The caster boxes after instances moved: an instance caster's box is its level's
/// `triangle_bounds` (the same vertices [`caster_boxes`] grows over, so the same box as a
/// fresh build's); the static level's casters keep theirs.
pub fn follow_moved_casters(
    boxes: &mut [crate::math::geometry::Aabb],
    objects: &[u32],
    levels: &[crate::device::acceleration::Level],
) {
    for (b, object) in boxes.iter_mut().zip(objects) {
        if let Some(l) = levels.iter().find(|l| l.object == Some(*object as usize)) {
            *b = l.triangle_bounds;
        }
    }
}

/// AdaptiveCaustics' constructor. The technique *is* a [`CausticMap`] (the same atlas,
/// gather, final pass, outputs and update methods) whose photons come from seed 004's
/// traversal, and whose registry and stats name is `adaptive-caustics`.
pub struct AdaptiveCaustics;

impl AdaptiveCaustics {
    /// Validates `settings`, uploads the scene, lays out the atlas and makes the
    /// traversal's buffers: the [`CausticMap`] that runs the traversal (the atlas target;
    /// [`AdaptiveCaustics::build_screen`] for the screen).
    pub fn build(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: AdaptiveCausticsSettings,
    ) -> Result<CausticMap, Error> {
        settings.validate()?;
        if settings.deposit != AdaptiveDeposit::Atlas {
            return Err(Error::InvalidParameter(
                "adaptive-caustics: deposit \"screen\" makes an Sspm frame \
                 (AdaptiveCaustics::build_screen)"
                    .into(),
            ));
        }
        let map = settings.map.clone();
        CausticMap::build(backend, scene, map, Some(settings))
    }
}

/// The registry's constructor: `settings` is a JSON object of
/// [`AdaptiveCausticsSettings`] fields (CausticMap's at the top level; missing fields
/// take their defaults, unknown ones are an error).
pub fn create(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn Technique>, Error> {
    let settings = AdaptiveCausticsSettings::from_json(settings)?;
    Ok(match settings.deposit {
        AdaptiveDeposit::Atlas => Box::new(AdaptiveCaustics::build(backend, scene, settings)?),
        AdaptiveDeposit::Screen => Box::new(AdaptiveScreen::new(backend, scene, settings)?),
    })
}

#[cfg(test)]
mod tests {
    use crate::device::device_scene::DeviceScene;
    use crate::scene::builtin::builtin;
    use crate::scene::{Shape, Transform};
    use glam::{Quat, Vec3};

    /// A moved instance caster's box is its level's triangle bounds, the box a fresh
    /// build of the moved scene gives it ([`super::follow_moved_casters`]).
    #[test]
    fn caster_boxes_follow_moved_instances() {
        let mut s = builtin("cornell").unwrap();
        for o in s.objects.iter_mut().filter(|o| o.name.ends_with("ball")) {
            if let Shape::Sphere { center, .. } = &mut o.shape {
                let c = std::mem::replace(center, Vec3::ZERO);
                o.transform = Some(Transform::from_translation(c));
            }
        }
        let ds = DeviceScene::build(&s, Default::default()).unwrap();
        let (objects, mut boxes): (Vec<u32>, Vec<_>) =
            super::caster_boxes_by_object(&ds).into_iter().unzip();
        let mut instances = ds.instances.clone();
        let to = Transform {
            translation: Vec3::new(0.1, 0.5, 0.2),
            rotation: Quat::from_rotation_x(0.3),
            scale: Vec3::splat(0.7),
        };
        instances.move_instances(&[(5, to)]).unwrap();
        super::follow_moved_casters(&mut boxes, &objects, &instances.levels);
        s.objects[5].transform = Some(to);
        let fresh = DeviceScene::build(&s, Default::default()).unwrap();
        assert_eq!(boxes, super::caster_boxes(&fresh));
    }
}
