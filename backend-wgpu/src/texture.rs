//! Embedding: writes a result image (linear RGBA f32, row-major from the top-left) into a
//! caller's 2-D texture through a storage-texture compute pass, so the caller's renderer
//! can sample the caustics (or the composite) directly, with no host round trip.

use crate::WgpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::handle::ImageBuf;

/// The copy shader for a storage texture format.
fn source(format: &str) -> String {
    format!(
        "@group(0) @binding(0) var<storage, read> image: array<vec4<f32>>;\n\
         @group(0) @binding(1) var dest: texture_storage_2d<{format}, write>;\n\
         @compute @workgroup_size(8, 8)\n\
         fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             let size = textureDimensions(dest);\n\
             if (id.x >= size.x || id.y >= size.y) {{ return; }}\n\
             textureStore(dest, vec2<i32>(id.xy), image[id.y * size.x + id.x]);\n\
         }}\n"
    )
}

impl WgpuBackend {
    /// Writes `image` (a `width x height` result of this backend, e.g.
    /// `Sspm::images().filtered_caustics`) into `target`, a 2-D texture of the same size
    /// with `STORAGE_BINDING` usage and format `Rgba16Float` or `Rgba32Float`. The work is
    /// submitted on the backend's queue (the caller's, when embedded).
    pub fn write_image_to_texture(
        &mut self,
        image: ImageBuf,
        target: &wgpu::Texture,
    ) -> Result<(), BackendError> {
        let mut enc = self.device.create_command_encoder(&Default::default());
        self.encode_image_to_texture(image, target, &mut enc)?;
        self.queue.submit([enc.finish()]);
        self.check_uncaptured()
    }

    /// As [`WgpuBackend::write_image_to_texture`], recorded into the caller's `enc` (after
    /// the frame it encoded with [`WgpuBackend::encode`]) instead of submitted: the host's
    /// frame loop submits once.
    pub fn encode_image_to_texture(
        &mut self,
        image: ImageBuf,
        target: &wgpu::Texture,
        enc: &mut wgpu::CommandEncoder,
    ) -> Result<(), BackendError> {
        let format = target.format();
        let name = match format {
            wgpu::TextureFormat::Rgba16Float => "rgba16float",
            wgpu::TextureFormat::Rgba32Float => "rgba32float",
            other => {
                return Err(BackendError::Unsupported(format!(
                    "texture format {other:?}; use Rgba16Float or Rgba32Float"
                )))
            }
        };
        let (w, h) = (target.width(), target.height());
        if image.len as u64 != w as u64 * h as u64 {
            return Err(BackendError::BadArgument(format!(
                "image has {} texels, the texture {w}x{h}",
                image.len
            )));
        }
        if !target
            .usage()
            .contains(wgpu::TextureUsages::STORAGE_BINDING)
        {
            return Err(BackendError::BadArgument(
                "the target texture needs STORAGE_BINDING usage".into(),
            ));
        }
        if !self.texture_pipelines.contains_key(&format) {
            let module = self
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("write_image_to_texture"),
                    source: wgpu::ShaderSource::Wgsl(source(name).into()),
                });
            let pipeline = self
                .device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("write_image_to_texture"),
                    layout: None,
                    module: &module,
                    entry_point: Some("main"),
                    compilation_options: Default::default(),
                    cache: None,
                });
            self.texture_pipelines.insert(format, pipeline);
        }
        let pipeline = &self.texture_pipelines[&format];
        let buffer = &self.buffers.get(image.id)?.buffer;
        let view = target.create_view(&Default::default());
        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("write_image_to_texture"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer,
                        offset: 0,
                        size: std::num::NonZeroU64::new(
                            image.bytes().max(crate::memory::MIN_BINDING_BYTES),
                        ),
                    }),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
            ],
        });
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn copy_shader_validates_for_both_formats() {
        for f in ["rgba16float", "rgba32float"] {
            let module = naga::front::wgsl::parse_str(&super::source(f))
                .unwrap_or_else(|e| panic!("{f}: {e}"));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::default(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{f}: {e:?}"));
        }
    }
}
