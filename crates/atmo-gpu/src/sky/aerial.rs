//! The aerial perspective's froxels on the GPU (`atmo::sky::aerial`): a compute pass
//! into two 3-D textures a caller's shader samples.

use std::sync::Arc;

use super::*;

/// The aerial perspective's froxels on the GPU ([`atmo::sky::aerial`]): the marked rays
/// of an [`AerialRays`] uploaded once; per sun and camera, one invocation per froxel
/// column reads its row's ray at its angle to the sun, as the CPU does.
pub struct GpuAerial {
    pub(super) rays: Arc<AerialRays>,
    pub(super) marked: wgpu::Buffer,
    pub(super) params: AerialParams,
    pub(super) pipeline: wgpu::ComputePipeline,
}

impl GpuAerial {
    /// Uploads `rays` (made by `sky`'s model) for `sky`'s device; shared rays (an `Arc`)
    /// are kept without a copy.
    pub fn new<M: Borrow<SkyModel>>(
        gpu: &Gpu,
        sky: &GpuSkyModel<M>,
        rays: impl Into<Arc<AerialRays>>,
    ) -> Result<Self, GpuError> {
        let rays = rays.into();
        let arrays = rays.arrays();
        if arrays.lanes != sky.sky_params.lanes as usize {
            return Err(atmo::Error::Invalid(
                "the aerial rays were made for another atmosphere than the sky's".into(),
            )
            .into());
        }
        let mut data: Vec<[f32; 4]> = Vec::new();
        let mut at = |values: &[[f32; 4]]| {
            let start = data.len() as u32;
            data.extend_from_slice(values);
            start
        };
        let params = AerialParams {
            white: [0.0; 4],
            sin_sun: 0.0,
            columns: 0,
            slices: rays.slices_m().len() as u32,
            width: 0,
            rows_at: at(&arrays.rows),
            samples_at: at(&arrays.samples),
            rayleigh_at: at(&arrays.rayleigh),
            mie_at: at(&arrays.mie),
            marks_at: at(&arrays.marks),
            pad1: 0,
            pad2: 0,
            pad3: 0,
        };
        let marked = gpu.storage(
            "the aerial rays",
            bytemuck::cast_slice(&data),
            "aerial rows or slices",
        )?;
        let module = wgsl::module(gpu, "sky_shells.wgsl")?;
        Ok(GpuAerial {
            rays,
            marked,
            params,
            pipeline: gpu.compute_pipeline(&module, "aerial_main", None)?,
        })
    }

    /// The marked rays uploaded (the CPU's froxels come from them too).
    pub fn rays(&self) -> &AerialRays {
        &self.rays
    }

    /// Records into `encoder` the froxels of `camera` (one column per pixel: a coarse
    /// camera, e.g. 32 columns across) for `sun`, written into `targets` (made for the
    /// camera's size and these rays' slices): no read-back, for a caller's shader to
    /// sample at its pixel and distance.
    pub fn prepare<M: Borrow<SkyModel>>(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sky: &GpuSkyModel<M>,
        sun: Sun,
        camera: &Camera,
        targets: &AerialTextures,
    ) -> Result<(), GpuError> {
        let slices = self.rays.slices_m().len() as u32;
        if targets.size != (camera.width, camera.height, slices) {
            return Err(atmo::Error::Invalid(format!(
                "the aerial textures are {:?} froxels, the camera and the rays ask for {:?}",
                targets.size,
                (camera.width, camera.height, slices)
            ))
            .into());
        }
        let columns: Vec<[f32; 2]> = self
            .rays
            .columns(sun, camera)
            .into_iter()
            .map(|(row, nu)| [row as f32, nu as f32])
            .collect();
        let atmosphere = sky.model().atmosphere();
        let solar: Vec<f32> = atmosphere
            .solar_irradiance
            .iter()
            .map(|&e| e as f32)
            .collect();
        let white = sky.to_rgb.rgb(&solar);
        let params = AerialParams {
            white: [white[0], white[1], white[2], 0.0],
            sin_sun: sun.elevation().sin() as f32,
            columns: columns.len() as u32,
            width: camera.width,
            ..self.params
        };
        let uniform = gpu.uniform("the aerial pass", &params);
        let column_buffer = gpu.storage(
            "the froxel columns",
            bytemuck::cast_slice(&columns),
            "the camera's width and height",
        )?;
        let views = [&targets.inscatter, &targets.transmittance]
            .map(|t| t.create_view(&Default::default()));
        // Bindings 0 and 1 are the shell pass's; 2 (its map) is not read here.
        let mut entries: Vec<wgpu::BindGroupEntry> = [
            (0, &sky.uniforms[0]),
            (1, &sky.data),
            (3, &uniform),
            (4, &self.marked),
            (5, &column_buffer),
        ]
        .into_iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
        entries.extend(
            views
                .iter()
                .zip([6, 7])
                .map(|(view, binding)| wgpu::BindGroupEntry {
                    binding,
                    resource: wgpu::BindingResource::TextureView(view),
                }),
        );
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("the aerial pass"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((columns.len() as u32).div_ceil(64), 1, 1);
        Ok(())
    }

    /// The froxels of `camera` for `sun`, as [`AerialRays::froxels`] gives them: the
    /// pass of [`GpuAerial::prepare`] into textures of its own, read back.
    pub fn froxels<M: Borrow<SkyModel>>(
        &self,
        gpu: &Gpu,
        sky: &GpuSkyModel<M>,
        sun: Sun,
        camera: &Camera,
    ) -> Result<Froxels, GpuError> {
        let size = (
            camera.width,
            camera.height,
            self.rays.slices_m().len() as u32,
        );
        let targets = AerialTextures::new(gpu, size)?;
        gpu.scoped("the aerial pass", || {
            let mut encoder = gpu
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("the aerial pass"),
                });
            self.prepare(gpu, &mut encoder, sky, sun, camera, &targets)?;
            gpu.queue.submit([encoder.finish()]);
            Ok::<(), GpuError>(())
        })??;
        let read = |texture: &wgpu::Texture| -> Result<Vec<Vec3>, GpuError> {
            let bytes = gpu.read_texture_layers("the froxels", texture, size)?;
            let values: &[f32] = bytemuck::cast_slice(&bytes);
            Ok(values
                .chunks(4)
                .map(|v| Vec3::new(v[0], v[1], v[2]))
                .collect())
        };
        Ok(Froxels {
            width: camera.width,
            height: camera.height,
            slices_m: self.rays.slices_m().to_vec(),
            inscatter: read(&targets.inscatter)?,
            transmittance: read(&targets.transmittance)?,
        })
    }
}

/// WGSL for a caller's shader to read [`AerialTextures`]: `aerial_light(transmittance,
/// inscatter, sampler, uv, d, far, slices)` gives the transmittance and the in-scattered
/// radiance at the picture's point `uv` and distance `d` (`far`: the last slice, m).
/// Put it in the caller's source, after any `enable` directive.
pub const AERIAL_LIGHT_WGSL: &str = include_str!("../../shaders/aerial_light.wgsl");

/// The aerial perspective's froxels as two 3-D RGBA f32 textures of
/// `(columns across, columns down, slices)`: the in-scattered radiance (linear sRGB, the
/// sky's units) and the transmittance, which [`GpuAerial::prepare`] writes and a
/// caller's shader samples (linear filtering of f32 textures needs the device's
/// `FLOAT32_FILTERABLE`): a surface `d` m away at a pixel is seen as `T L + S`.
pub struct AerialTextures {
    pub inscatter: wgpu::Texture,
    pub transmittance: wgpu::Texture,
    /// Columns across, columns down, slices.
    pub size: (u32, u32, u32),
}

impl AerialTextures {
    /// Textures for `size` froxels (checked against the device's 3-D texture limit).
    pub fn new(gpu: &Gpu, size: (u32, u32, u32)) -> Result<Self, GpuError> {
        let side = size.0.max(size.1).max(size.2) as u64;
        let max = gpu.limits().max_texture_dimension_3d as u64;
        gpu.check_limit(
            "the aerial textures",
            side,
            max,
            "max_texture_dimension_3d",
            "the froxel grid",
        )?;
        let [inscatter, transmittance] =
            ["the aerial in-scatter", "the aerial transmittance"].map(|label| {
                gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size.0,
                        height: size.1,
                        depth_or_array_layers: size.2,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D3,
                    format: wgpu::TextureFormat::Rgba32Float,
                    usage: wgpu::TextureUsages::STORAGE_BINDING
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            });
        Ok(AerialTextures {
            inscatter,
            transmittance,
            size,
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_froxels_lookup_is_valid_wgsl() {
        let module = naga::front::wgsl::parse_str(super::AERIAL_LIGHT_WGSL)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(super::AERIAL_LIGHT_WGSL)));
        let mut validator = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        );
        validator.validate(&module).unwrap();
        assert!(module
            .functions
            .iter()
            .any(|(_, f)| f.name.as_deref() == Some("aerial_light")));
    }
}
