//! Bevy's world in caustica's terms: materials, lights, meshes, transforms and the camera.
//! Pure functions of Bevy values, unit-tested below; the plugin calls them from its
//! systems.
//!
//! Units. caustica's radiometry is linear (it never converts between watts and lumens), so
//! Bevy's photometric units go through it unchanged and come out photometric:
//! - a `PointLight` or `SpotLight` of `intensity` lumens with linear colour `c` is a
//!   caustica light of `c * intensity / (4 pi)` per steradian, as Bevy itself converts
//!   them (`bevy_pbr::render::light`, lumens to candela, a spot light as the point light
//!   it is cut from);
//! - a `DirectionalLight` of `illuminance` lux is an irradiance of `c * illuminance`;
//! - caustica's caustic radiance then comes out in nits (cd/m^2), which the plugin
//!   multiplies by the camera's exposure, as Bevy's PBR shader does with its own light,
//!   before adding it to the view's HDR target.
//!
//! Positions are Bevy's world units (metres), used as caustica's scene units.

use caustica::glam as cg;
use caustica::scene::{Light, Material, MeshData, Transform};

/// Bevy's math types (bevy's glam) as plain arrays, so that this module does not care
/// which glam version either side uses.
pub type V3 = [f32; 3];

fn v3(a: V3) -> cg::Vec3 {
    cg::Vec3::from_array(a)
}

/// What the plugin reads of a `StandardMaterial` (linear colours).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialInput {
    /// `base_color` in linear RGB.
    pub base_color: V3,
    /// `metallic`.
    pub metallic: f32,
    /// `perceptual_roughness`.
    pub perceptual_roughness: f32,
    /// `specular_transmission`.
    pub specular_transmission: f32,
    /// `ior`.
    pub ior: f32,
    /// `thickness` (world units).
    pub thickness: f32,
    /// `attenuation_color` in linear RGB.
    pub attenuation_color: V3,
    /// `attenuation_distance` (world units; infinite: no absorption).
    pub attenuation_distance: f32,
    /// `unlit`.
    pub unlit: bool,
}

/// A material at most this rough and at least this metallic is a mirror.
pub const MIRROR_MAX_ROUGHNESS: f32 = 0.1;
/// See [`MIRROR_MAX_ROUGHNESS`].
pub const MIRROR_MIN_METALLIC: f32 = 0.9;

/// caustica's material for a `StandardMaterial`, and what of it caustica cannot represent
/// (a line to warn once, if any).
///
/// - `specular_transmission > 0`: a smooth dielectric of index `ior` whose Beer-Lambert
///   absorption is `-ln(attenuation_color) / attenuation_distance` per channel (Bevy's
///   volume attenuation: light that travels `attenuation_distance` inside keeps
///   `attenuation_color` of itself). caustica's dielectric transmits everything Fresnel
///   does not reflect: a `specular_transmission` below 1 is taken as 1 (warned).
/// - `metallic >= 0.9` and `perceptual_roughness <= 0.1`: a mirror reflecting
///   `base_color`.
/// - otherwise a Lambertian receiver of albedo `base_color * (1 - metallic)`, Bevy's
///   diffuse colour; `unlit` surfaces receive nothing (albedo 0: Bevy does not light them).
pub fn material(m: &MaterialInput) -> (Material, Option<String>) {
    let clamp01 = |c: V3| v3(c).clamp(cg::Vec3::ZERO, cg::Vec3::ONE);
    if m.specular_transmission > 0.0 && !m.unlit {
        let mut notes = Vec::new();
        if m.specular_transmission < 1.0 {
            notes.push(format!(
                "specular_transmission {} is taken as 1 (caustica's glass transmits all but the Fresnel reflection)",
                m.specular_transmission
            ));
        }
        let absorption = if m.attenuation_distance.is_finite() && m.attenuation_distance > 0.0 {
            let c = v3(m.attenuation_color).clamp(cg::Vec3::splat(1e-6), cg::Vec3::ONE);
            cg::Vec3::from_array(c.to_array().map(|x| -x.ln() / m.attenuation_distance))
        } else {
            cg::Vec3::ZERO
        };
        if absorption == cg::Vec3::ZERO && v3(m.base_color).min_element() < 0.999 {
            notes.push(
                "a tinted base_color on glass does not tint its caustics; use attenuation_color and attenuation_distance".into(),
            );
        }
        let ior = if m.ior.is_finite() && m.ior > 0.0 {
            m.ior
        } else {
            1.5
        };
        let note = (!notes.is_empty()).then(|| notes.join("; "));
        return (
            Material::Dielectric {
                ior,
                cauchy_b: 0.0,
                absorption,
                ior_model: Default::default(),
            },
            note,
        );
    }
    if m.unlit {
        return (
            Material::Diffuse {
                albedo: cg::Vec3::ZERO,
            },
            None,
        );
    }
    if m.metallic >= MIRROR_MIN_METALLIC && m.perceptual_roughness <= MIRROR_MAX_ROUGHNESS {
        return (
            Material::Mirror {
                reflectance: clamp01(m.base_color),
            },
            None,
        );
    }
    let albedo = clamp01(m.base_color) * (1.0 - m.metallic.clamp(0.0, 1.0));
    let note = (m.metallic > 0.0).then(|| {
            format!(
                "metallic {} with perceptual_roughness {} is neither a mirror (metallic >= {MIRROR_MIN_METALLIC}, roughness <= {MIRROR_MAX_ROUGHNESS}) nor diffuse: its glossy reflection casts no caustic",
                m.metallic, m.perceptual_roughness
            )
        });
    (Material::Diffuse { albedo }, note)
}

/// One of Bevy's lights, as the plugin reads it (linear colour, world transform).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightInput {
    /// `PointLight`: `intensity` in lumens.
    Point {
        /// Linear colour.
        color: V3,
        /// Lumens.
        intensity: f32,
        /// World position.
        position: V3,
    },
    /// `SpotLight`: `intensity` in lumens; angles are half-angles in radians; it shines
    /// along its transform's forward (-z).
    Spot {
        /// Linear colour.
        color: V3,
        /// Lumens.
        intensity: f32,
        /// World position.
        position: V3,
        /// World direction it shines in.
        direction: V3,
        /// Half-angle of full intensity (radians).
        inner_angle: f32,
        /// Half-angle at which it reaches zero (radians).
        outer_angle: f32,
    },
    /// `DirectionalLight`: `illuminance` in lux, travelling along `direction`.
    Directional {
        /// Linear colour.
        color: V3,
        /// Lux.
        illuminance: f32,
        /// World direction the light travels (the transform's forward).
        direction: V3,
    },
}

/// caustica's light for one of Bevy's (see the module's units). A light dimmer than
/// caustica's smallest power (`scene::limits::MIN_INTENSITY`, 2^-60 in its brightest
/// channel: a light fading out) is off (zero power), not an invalid scene.
pub fn light(l: &LightInput) -> Light {
    let off_below_bound = |p: cg::Vec3| {
        if p.max_element() < caustica::scene::limits::MIN_INTENSITY {
            cg::Vec3::ZERO
        } else {
            p
        }
    };
    let per_sr = |c: V3, lumens: f32| {
        off_below_bound(v3(c).max(cg::Vec3::ZERO) * lumens.max(0.0) / (4.0 * std::f32::consts::PI))
    };
    match *l {
        LightInput::Point {
            color,
            intensity,
            position,
        } => Light::Point {
            position: v3(position),
            intensity: per_sr(color, intensity),
        },
        LightInput::Spot {
            color,
            intensity,
            position,
            direction,
            inner_angle,
            outer_angle,
        } => {
            let outer = outer_angle.to_degrees().clamp(0.01, 180.0);
            Light::Spot {
                position: v3(position),
                direction: v3(direction),
                intensity: per_sr(color, intensity),
                inner_angle_deg: inner_angle.to_degrees().clamp(0.0, outer),
                outer_angle_deg: outer,
            }
        }
        LightInput::Directional {
            color,
            illuminance,
            direction,
        } => Light::Directional {
            direction: v3(direction),
            irradiance: off_below_bound(v3(color).max(cg::Vec3::ZERO) * illuminance.max(0.0)),
            projection_volume: None,
        },
    }
}

/// caustica's transform from a Bevy `GlobalTransform`'s scale, rotation (`[x, y, z, w]`)
/// and translation.
pub fn transform(scale: V3, rotation: [f32; 4], translation: V3) -> Transform {
    Transform {
        translation: v3(translation),
        rotation: cg::Quat::from_array(rotation).normalize(),
        scale: v3(scale),
    }
}

/// A Bevy mesh's triangles, as caustica takes them (object space).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshGeometry {
    /// Vertex positions.
    pub positions: MeshData<cg::Vec3>,
    /// Per-vertex normals, or empty.
    pub normals: MeshData<cg::Vec3>,
    /// Per-vertex uvs, or empty.
    pub uvs: MeshData<cg::Vec2>,
    /// Triangles.
    pub indices: MeshData<[u32; 3]>,
}

/// Why a mesh cannot be taken.
pub type MeshRefusal = String;

/// A Bevy mesh's triangles (`TriangleList` only). Refused with the reason: another
/// topology, no positions, data extracted to the render world only
/// (`RenderAssetUsages::RENDER_WORLD`), an index out of range, or no triangle.
pub fn mesh_geometry(mesh: &bevy::mesh::Mesh) -> Result<MeshGeometry, MeshRefusal> {
    use bevy::mesh::{Mesh, MeshAccessError, PrimitiveTopology, VertexAttributeValues};
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return Err(format!(
            "topology {:?}: caustica takes TriangleList meshes",
            mesh.primitive_topology()
        ));
    }
    let extracted = |e: MeshAccessError| match e {
        MeshAccessError::ExtractedToRenderWorld => {
            "its data lives in the render world only (RenderAssetUsages without MAIN_WORLD)"
                .to_string()
        }
        MeshAccessError::NotFound => "data not found".to_string(),
    };
    let positions: Vec<cg::Vec3> = match mesh
        .try_attribute_option(Mesh::ATTRIBUTE_POSITION)
        .map_err(extracted)?
    {
        Some(VertexAttributeValues::Float32x3(p)) => p.iter().map(|&a| v3(a)).collect(),
        Some(other) => {
            return Err(format!(
                "positions as {:?}: caustica takes Float32x3",
                other.enum_variant_name()
            ))
        }
        None => return Err("no vertex positions".into()),
    };
    let normals: Vec<cg::Vec3> = match mesh
        .try_attribute_option(Mesh::ATTRIBUTE_NORMAL)
        .map_err(extracted)?
    {
        Some(VertexAttributeValues::Float32x3(n)) if n.len() == positions.len() => {
            n.iter().map(|&a| v3(a)).collect()
        }
        _ => Vec::new(),
    };
    let uvs: Vec<cg::Vec2> = match mesh
        .try_attribute_option(Mesh::ATTRIBUTE_UV_0)
        .map_err(extracted)?
    {
        Some(VertexAttributeValues::Float32x2(u)) if u.len() == positions.len() => {
            u.iter().map(|&a| cg::Vec2::from_array(a)).collect()
        }
        _ => Vec::new(),
    };
    let flat: Vec<usize> = match mesh.try_indices_option().map_err(extracted)? {
        Some(i) => i.iter().collect(),
        None => (0..positions.len()).collect(),
    };
    let n = positions.len();
    if let Some(bad) = flat.iter().find(|&&i| i >= n) {
        return Err(format!("index {bad} beyond its {n} vertices"));
    }
    let indices: Vec<[u32; 3]> = flat
        .chunks_exact(3)
        .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
        .collect();
    if indices.is_empty() {
        return Err("no triangle".into());
    }
    Ok(MeshGeometry {
        positions: positions.into(),
        normals: normals.into(),
        uvs: uvs.into(),
        indices: indices.into(),
    })
}

/// caustica's camera for a view: Bevy's `world_from_view` (the camera's world matrix)
/// and `clip_from_view` (its projection, infinite reverse z), of `width x height` pixels.
/// Refused with caustica's reason (an orthographic or off-centre projection).
pub fn camera(
    world_from_view: [f32; 16],
    clip_from_view: [f32; 16],
    width: u32,
    height: u32,
) -> Result<caustica::scene::Camera, String> {
    let view = cg::Mat4::from_cols_array(&world_from_view).inverse();
    let proj = cg::Mat4::from_cols_array(&clip_from_view);
    caustica::scene::Camera::from_view_projection(view, proj, width, height)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glass() -> MaterialInput {
        MaterialInput {
            base_color: [1.0; 3],
            metallic: 0.0,
            perceptual_roughness: 0.0,
            specular_transmission: 1.0,
            ior: 1.5,
            thickness: 1.0,
            attenuation_color: [1.0; 3],
            attenuation_distance: f32::INFINITY,
            unlit: false,
        }
    }

    #[test]
    fn a_light_fading_below_causticas_smallest_power_is_off() {
        let point = |intensity: f32| {
            light(&LightInput::Point {
                color: [1.0; 3],
                intensity,
                position: [0.0; 3],
            })
        };
        let Light::Point { intensity, .. } = point(1e-30) else {
            panic!("a point light")
        };
        assert_eq!(intensity, cg::Vec3::ZERO);
        let Light::Point { intensity, .. } = point(1.0) else {
            panic!("a point light")
        };
        assert!(intensity.max_element() >= caustica::scene::limits::MIN_INTENSITY);
    }

    #[test]
    fn clear_glass_is_a_dielectric_without_absorption() {
        let (m, note) = material(&glass());
        assert_eq!(
            m,
            Material::Dielectric {
                ior: 1.5,
                cauchy_b: 0.0,
                absorption: cg::Vec3::ZERO,
                ior_model: Default::default(),
            }
        );
        assert!(note.is_none());
    }

    #[test]
    fn attenuation_is_beer_lambert() {
        let m = MaterialInput {
            attenuation_color: [0.5, 1.0, 0.25],
            attenuation_distance: 2.0,
            ior: 1.33,
            ..glass()
        };
        let (
            Material::Dielectric {
                ior, absorption, ..
            },
            _,
        ) = material(&m)
        else {
            panic!("not a dielectric")
        };
        assert_eq!(ior, 1.33);
        // after attenuation_distance inside, exp(-sigma d) is attenuation_color
        let kept = (-absorption * 2.0).exp();
        assert!(
            (kept - cg::Vec3::new(0.5, 1.0, 0.25)).abs().max_element() < 1e-5,
            "{kept}"
        );
    }

    #[test]
    fn partial_transmission_and_tinted_glass_are_noted() {
        let m = MaterialInput {
            specular_transmission: 0.5,
            base_color: [1.0, 0.2, 0.2],
            ..glass()
        };
        let (m, note) = material(&m);
        assert!(matches!(m, Material::Dielectric { .. }));
        let note = note.expect("a note");
        assert!(note.contains("specular_transmission") && note.contains("attenuation_color"));
    }

    #[test]
    fn smooth_metal_is_a_mirror_and_the_rest_diffuse() {
        let metal = MaterialInput {
            base_color: [0.9, 0.8, 0.7],
            metallic: 1.0,
            perceptual_roughness: 0.05,
            specular_transmission: 0.0,
            ..glass()
        };
        assert_eq!(
            material(&metal).0,
            Material::Mirror {
                reflectance: cg::Vec3::new(0.9, 0.8, 0.7)
            }
        );
        let rough = MaterialInput {
            perceptual_roughness: 0.5,
            ..metal
        };
        let (m, note) = material(&rough);
        assert_eq!(
            m,
            Material::Diffuse {
                albedo: cg::Vec3::ZERO
            }
        );
        assert!(note.is_some());
        let paint = MaterialInput {
            base_color: [0.8, 0.5, 0.2],
            metallic: 0.0,
            perceptual_roughness: 0.6,
            specular_transmission: 0.0,
            ..glass()
        };
        assert_eq!(
            material(&paint),
            (
                Material::Diffuse {
                    albedo: cg::Vec3::new(0.8, 0.5, 0.2)
                },
                None
            )
        );
        let unlit = MaterialInput {
            unlit: true,
            ..paint
        };
        assert_eq!(
            material(&unlit).0,
            Material::Diffuse {
                albedo: cg::Vec3::ZERO
            }
        );
    }

    #[test]
    fn lumens_become_intensity_per_steradian_and_lux_irradiance() {
        let four_pi = 4.0 * std::f32::consts::PI;
        let Light::Point {
            intensity,
            position,
        } = light(&LightInput::Point {
            color: [1.0, 0.5, 0.0],
            intensity: 1000.0 * four_pi,
            position: [1.0, 2.0, 3.0],
        })
        else {
            panic!()
        };
        assert!(
            (intensity - cg::Vec3::new(1000.0, 500.0, 0.0))
                .abs()
                .max_element()
                < 1e-2
        );
        assert_eq!(position, cg::Vec3::new(1.0, 2.0, 3.0));
        let Light::Spot {
            intensity,
            inner_angle_deg,
            outer_angle_deg,
            direction,
            ..
        } = light(&LightInput::Spot {
            color: [1.0; 3],
            intensity: four_pi,
            position: [0.0; 3],
            direction: [0.0, -1.0, 0.0],
            inner_angle: 0.0,
            outer_angle: std::f32::consts::FRAC_PI_4,
        })
        else {
            panic!()
        };
        assert!((intensity - cg::Vec3::ONE).abs().max_element() < 1e-6);
        assert_eq!((inner_angle_deg, direction), (0.0, cg::Vec3::NEG_Y));
        assert!((outer_angle_deg - 45.0).abs() < 1e-4);
        let Light::Directional { irradiance, .. } = light(&LightInput::Directional {
            color: [1.0, 1.0, 0.5],
            illuminance: 10_000.0,
            direction: [0.0, -1.0, 0.0],
        }) else {
            panic!()
        };
        assert_eq!(irradiance, cg::Vec3::new(10_000.0, 10_000.0, 5_000.0));
    }

    #[test]
    fn meshes_caustica_cannot_take_are_refused() {
        use bevy::asset::RenderAssetUsages;
        use bevy::mesh::{Mesh, PrimitiveTopology};
        let lines = Mesh::new(PrimitiveTopology::LineList, RenderAssetUsages::default())
            .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, vec![[0.0f32; 3]; 2]);
        assert!(mesh_geometry(&lines).unwrap_err().contains("topology"));
        let empty = Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        );
        assert!(mesh_geometry(&empty).unwrap_err().contains("positions"));
        let tri = Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            vec![[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        );
        let g = mesh_geometry(&tri).expect("a triangle");
        assert_eq!(*g.indices, vec![[0, 1, 2]]);
    }

    #[test]
    fn a_bevy_perspective_camera_becomes_a_pinhole() {
        use cg::camera::rh::{proj::directx, view::look_at_mat4};
        let eye = cg::Vec3::new(0.0, 2.0, 5.0);
        let world_from_view = look_at_mat4(eye, cg::Vec3::ZERO, cg::Vec3::Y).inverse();
        // Bevy's projection: infinite reverse z
        let proj = directx::perspective_infinite_reverse(0.8, 16.0 / 9.0, 0.1);
        let c = camera(
            world_from_view.to_cols_array(),
            proj.to_cols_array(),
            160,
            90,
        )
        .expect("a pinhole");
        assert!((c.position - eye).length() < 1e-4);
        assert!((c.fov_y_deg - 0.8f32.to_degrees()).abs() < 1e-3);
        let forward = (c.target - c.position).normalize();
        assert!((forward - (-eye).normalize()).length() < 1e-4);
    }
}
