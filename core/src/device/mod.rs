//! The device layer: what crosses to a backend. [`layout`]: the `#[repr(C)]` Pod element
//! layouts shared with every shader (and the functions over them that shaders mirror);
//! [`layout_table`]: a description of those layouts (fields, offsets, 4-byte leaves) that
//! the shader crates' layout tests compare with; [`shader_constants`]: the constants the
//! shaders share with core, listed once; [`shader_layouts`]: the generator of the shaders'
//! declarations of both; [`device_scene`]: a scene flattened to
//! those layouts with its two-level CWBVH ([`acceleration`]: how the node buffer holds it;
//! [`bvh_cache`]: bottom levels kept between builds); [`handle`]: typed opaque buffer handles; [`launch`]: a
//! lowered kernel launch; [`error`]: typed failures. Imports only [`crate::math`] and
//! [`crate::scene`].

pub mod acceleration;
pub mod bvh_cache;
pub mod caster_spheres;
pub mod device_scene;
pub mod error;
pub mod handle;
pub mod launch;
pub mod layout;
pub mod layout_table;
pub mod placement;
pub mod shader_constants;
pub mod shader_layouts;

pub use device_scene::DeviceScene;
pub use error::{host_bytes, BackendError};
pub use handle::{Buf, ImageBuf, ResourceId, SceneArgs};
