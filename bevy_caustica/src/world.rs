//! The main world's side: Bevy's meshes, materials and lights read into a snapshot of
//! caustica's scene parts (after transform propagation), which the render world takes in
//! its extract step. Meshes are converted once per asset (again when the asset changes);
//! what cannot be represented is warned about once.

use crate::convert::{self, LightInput, MaterialInput, MeshGeometry};
use bevy::asset::AssetEvent;
use bevy::light::NotShadowCaster;
use bevy::prelude::*;
use bevy::transform::TransformSystems;
use caustica::scene::{Light, Material, Transform as CTransform};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

/// One object of caustica's scene.
#[derive(Clone, Debug)]
pub(crate) struct ObjectSnap {
    /// Shared: a moved object keeps the same `Arc` (the render world compares pointers).
    pub mesh: Arc<MeshGeometry>,
    pub material: Material,
    pub transform: CTransform,
}

/// Bevy's world in caustica's terms, remade when something in it changed.
#[derive(Resource, Clone, Debug, Default)]
pub(crate) struct WorldSnapshot {
    /// By entity, in entity order (the object order of caustica's scene).
    pub objects: BTreeMap<Entity, ObjectSnap>,
    pub lights: Vec<Light>,
}

/// Converted meshes by asset, and what was warned about.
#[derive(Resource, Default)]
struct MeshCache {
    meshes: HashMap<AssetId<Mesh>, Result<Arc<MeshGeometry>, String>>,
    warned: HashSet<String>,
}

impl MeshCache {
    fn warn_once(&mut self, key: String, line: impl FnOnce() -> String) {
        if self.warned.insert(key) {
            warn!("bevy_caustica: {}", line());
        }
    }
}

pub(crate) fn build(app: &mut App) {
    app.init_resource::<WorldSnapshot>()
        .init_resource::<MeshCache>()
        .add_systems(
            PostUpdate,
            gather_world
                .after(TransformSystems::Propagate)
                .after(bevy::camera::visibility::VisibilitySystems::VisibilityPropagate),
        );
}

/// A `StandardMaterial` as [`convert::material`] reads it.
pub(crate) fn material_input(m: &StandardMaterial) -> MaterialInput {
    let lin = |c: Color| {
        let l = c.to_linear();
        [l.red, l.green, l.blue]
    };
    MaterialInput {
        base_color: lin(m.base_color),
        metallic: m.metallic,
        perceptual_roughness: m.perceptual_roughness,
        specular_transmission: m.specular_transmission,
        ior: m.ior,
        thickness: m.thickness,
        attenuation_color: lin(m.attenuation_color),
        attenuation_distance: m.attenuation_distance,
        unlit: m.unlit,
    }
}

fn lin(c: Color) -> [f32; 3] {
    let l = c.to_linear();
    [l.red, l.green, l.blue]
}

type ObjectQuery<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static Mesh3d,
        &'static MeshMaterial3d<StandardMaterial>,
        &'static GlobalTransform,
        Option<&'static InheritedVisibility>,
        Has<NotShadowCaster>,
    ),
>;

#[allow(clippy::too_many_arguments)]
fn gather_world(
    mut snapshot: ResMut<WorldSnapshot>,
    mut cache: ResMut<MeshCache>,
    mut mesh_events: MessageReader<AssetEvent<Mesh>>,
    meshes: Res<Assets<Mesh>>,
    materials: Res<Assets<StandardMaterial>>,
    objects: ObjectQuery,
    points: Query<(&PointLight, &GlobalTransform, Option<&InheritedVisibility>)>,
    spots: Query<(&SpotLight, &GlobalTransform, Option<&InheritedVisibility>)>,
    suns: Query<(
        &DirectionalLight,
        &GlobalTransform,
        Option<&InheritedVisibility>,
    )>,
) {
    for e in mesh_events.read() {
        match e {
            AssetEvent::Modified { id }
            | AssetEvent::Removed { id }
            | AssetEvent::Unused { id } => {
                cache.meshes.remove(id);
            }
            _ => {}
        }
    }
    let visible = |v: Option<&InheritedVisibility>| v.is_none_or(|v| v.get());

    let mut objs = BTreeMap::new();
    for (entity, mesh3d, mat3d, gt, vis, no_shadow) in &objects {
        if !visible(vis) {
            continue;
        }
        let Some(mat) = materials.get(&mat3d.0) else {
            continue; // not loaded yet
        };
        let id = mesh3d.0.id();
        let geometry = match cache.meshes.get(&id) {
            Some(g) => g.clone(),
            None => {
                let Some(mesh) = meshes.get(id) else {
                    continue; // not loaded yet
                };
                let g = convert::mesh_geometry(mesh).map(Arc::new);
                cache.meshes.insert(id, g.clone());
                g
            }
        };
        let mesh = match geometry {
            Ok(g) => g,
            Err(why) => {
                cache.warn_once(format!("mesh {id:?}"), || {
                    format!("entity {entity}'s mesh is left out of caustica's scene: {why}")
                });
                continue;
            }
        };
        let (material, note) = convert::material(&material_input(mat));
        if let Some(note) = note {
            let key = format!("material {:?} {note}", mat3d.0.id());
            cache.warn_once(key, || format!("entity {entity}'s material: {note}"));
        }
        if material.is_specular() && no_shadow {
            cache.warn_once(format!("noshadow {entity}"), || {
                format!(
                    "entity {entity} is glass or a mirror with NotShadowCaster: Bevy lights what is behind it directly and caustica adds the light through it, counting it twice"
                )
            });
        }
        let (s, r, t) = gt.to_scale_rotation_translation();
        let transform = convert::transform(s.to_array(), r.to_array(), t.to_array());
        objs.insert(
            entity,
            ObjectSnap {
                mesh,
                material,
                transform,
            },
        );
    }

    let mut lights = Vec::new();
    let specular = objs.values().any(|o: &ObjectSnap| o.material.is_specular());
    let unshadowed = |cache: &mut MeshCache, kind: &str| {
        if specular {
            cache.warn_once(format!("unshadowed {kind}"), || {
                format!(
                    "a {kind} without shadow maps lights what is behind glass and mirrors directly, and caustica adds the light through them: that light is counted twice"
                )
            });
        }
    };
    for (l, gt, vis) in &points {
        if visible(vis) && l.intensity > 0.0 {
            if !l.shadow_maps_enabled {
                unshadowed(&mut cache, "PointLight");
            }
            if l.radius > 0.0 {
                cache.warn_once("point radius".into(), || {
                    "a PointLight's radius is taken as 0 (caustica's lights are points)".into()
                });
            }
            lights.push(convert::light(&LightInput::Point {
                color: lin(l.color),
                intensity: l.intensity,
                position: gt.translation().to_array(),
            }));
        }
    }
    for (l, gt, vis) in &spots {
        if visible(vis) && l.intensity > 0.0 {
            if !l.shadow_maps_enabled {
                unshadowed(&mut cache, "SpotLight");
            }
            if l.radius > 0.0 {
                cache.warn_once("spot radius".into(), || {
                    "a SpotLight's radius is taken as 0 (caustica's lights are points)".into()
                });
            }
            lights.push(convert::light(&LightInput::Spot {
                color: lin(l.color),
                intensity: l.intensity,
                position: gt.translation().to_array(),
                direction: gt.forward().to_array(),
                inner_angle: l.inner_angle,
                outer_angle: l.outer_angle,
            }));
        }
    }
    for (l, gt, vis) in &suns {
        if visible(vis) && l.illuminance > 0.0 {
            if !l.shadow_maps_enabled {
                unshadowed(&mut cache, "DirectionalLight");
            }
            lights.push(convert::light(&LightInput::Directional {
                color: lin(l.color),
                illuminance: l.illuminance,
                direction: gt.forward().to_array(),
            }));
        }
    }

    // change detection of the snapshot resource is the render world's signal
    let same_objects = objs.len() == snapshot.objects.len()
        && objs.iter().zip(&snapshot.objects).all(|((e, a), (f, b))| {
            e == f
                && Arc::ptr_eq(&a.mesh, &b.mesh)
                && a.material == b.material
                && a.transform == b.transform
        });
    if !same_objects || lights != snapshot.lights {
        snapshot.objects = objs;
        snapshot.lights = lights;
    }
}
