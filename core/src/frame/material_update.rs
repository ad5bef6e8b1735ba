//! Material parameters changed between frames without rebuilding geometry (the update
//! API): what the frame host checks and uploads for every technique.
//!
//! The acceleration structure, the triangles' material indices (by name, in the scene's
//! sorted order) and everything that depends on which objects are casters or receivers
//! (the casters' bounds that aim emission, CausticMap's atlas tiles) stay, so a material
//! may change its parameters and even switch between mirror and dielectric, but not
//! between diffuse and specular: that changes the casters and receivers, and needs a new
//! technique.

use crate::device::device_scene::gpu_material;
use crate::device::layout::GpuMaterial;
use crate::frame::error::Error;
use crate::frame::plan::SceneFeatures;
use crate::scene::{Material, Scene};
use std::collections::BTreeMap;

/// A checked material update: the scene with the new materials, their device form, and
/// whether the frame can keep its plan and constants.
#[derive(Clone, Debug)]
pub struct MaterialUpdate {
    /// The scene model with the new materials.
    pub model: Scene,
    /// The material table as the kernels read it (the scene's sorted order).
    pub gpu: Vec<GpuMaterial>,
    /// Whether any material disperses (a non-zero Cauchy B, or the Abbe model), as
    /// [`crate::device::device_scene::DeviceScene::has_dispersion`] counts it.
    pub has_dispersion: bool,
    /// The scene's features (and dispersion) are unchanged: the plan, the trace variant and
    /// the fixed-point quanta stay, and only the table is uploaded.
    pub same_plan: bool,
}

/// Checks `materials` against `scene`'s: the same names, each keeping whether it is
/// specular; every parameter valid (the scene validation's messages, located).
pub fn material_update(
    scene: &Scene,
    materials: &BTreeMap<String, Material>,
) -> Result<MaterialUpdate, Error> {
    let old: Vec<&String> = scene.materials.keys().collect();
    let new: Vec<&String> = materials.keys().collect();
    if old != new {
        return Err(Error::InvalidParameter(format!(
            "materials: the names must stay {old:?} (objects refer to them by name; got {new:?}): \
             create the technique again for other materials"
        )));
    }
    for (name, m) in materials {
        if m.is_specular() != scene.materials[name].is_specular() {
            return Err(Error::InvalidParameter(format!(
                "materials.{name}: switching between diffuse and specular changes the caustic \
                 casters and receivers: create the technique again"
            )));
        }
    }
    let mut model = scene.clone();
    model.materials = materials.clone();
    // (materials change no shape: the scene's meshes are not checked again)
    model
        .validate_except_shapes()
        .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
    let dispersive = |s: &Scene| s.materials.values().any(Material::is_dispersive);
    let has_dispersion = dispersive(&model);
    let same_plan = SceneFeatures::of(&model) == SceneFeatures::of(scene)
        && has_dispersion == dispersive(scene);
    let gpu = model.materials.values().map(gpu_material).collect();
    Ok(MaterialUpdate {
        model,
        gpu,
        has_dispersion,
        same_plan,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::builtin;

    #[test]
    fn only_parameters_may_change() {
        let s = builtin("sphere").unwrap();
        let mut m = s.materials.clone();
        if let Some(Material::Dielectric { ior, .. }) = m.get_mut("glass") {
            *ior = 1.33;
        }
        let u = material_update(&s, &m).unwrap();
        assert!(u.same_plan);
        let mut disp = m.clone();
        if let Some(Material::Dielectric { cauchy_b, .. }) = disp.get_mut("glass") {
            *cauchy_b = 0.004;
        }
        let u = material_update(&s, &disp).unwrap();
        assert!(!u.same_plan && u.has_dispersion);
        let mut wrong = m.clone();
        wrong.insert(
            "glass".into(),
            Material::Diffuse {
                albedo: glam::Vec3::ONE * 0.5,
            },
        );
        assert!(material_update(&s, &wrong).is_err());
        let mut renamed = m.clone();
        let g = renamed.remove("glass").unwrap();
        renamed.insert("glass2".into(), g);
        assert!(material_update(&s, &renamed).is_err());
        let mut bad = m;
        if let Some(Material::Dielectric { ior, .. }) = bad.get_mut("glass") {
            *ior = -1.0;
        }
        assert!(material_update(&s, &bad).is_err());
    }
}
