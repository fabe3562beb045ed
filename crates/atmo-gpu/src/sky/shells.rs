//! The sky by the shell method on the GPU (sky 3): per sun one compute pass sums every
//! view ray's shell crossings into the skylight map and the ground map.

use std::sync::Mutex;

use super::*;

/// A sky model uploaded: its sun-independent maps in one buffer, the shell pass, and the
/// skylight and ground maps it fills per sun; `M` is the model borrowed (`&SkyModel`)
/// or owned.
pub struct GpuSkyModel<M: Borrow<SkyModel>> {
    pub(super) model: M,
    pub(super) data: wgpu::Buffer,
    /// The shell pass's parameters without the sun, for the sky's and the ground's rays.
    pub(super) sky_params: ShellParams,
    pub(super) ground_params: ShellParams,
    pub(super) sky_grid: DirectionGrid,
    pub(super) ground_grid: DirectionGrid,
    pub(super) sky_map: wgpu::Buffer,
    pub(super) ground_map: wgpu::Buffer,
    pub(super) shells: wgpu::ComputePipeline,
    /// The shell pass's parameters of the sky's and the ground's grids, written per sun.
    pub(super) uniforms: [wgpu::Buffer; 2],
    /// The sun disc's spectrum to linear sRGB, made once (it integrates the CMFs).
    pub(super) to_rgb: SpectrumToRgb,
    /// The sun elevation whose maps were last recorded: `prepare` records them again
    /// only for another sun.
    pub(super) recorded: Mutex<Option<f64>>,
}

impl<M: Borrow<SkyModel>> GpuSkyModel<M> {
    /// Uploads `model`'s maps; an error for a model the GPU cannot evaluate yet
    /// (aerosols in the higher orders) or above the device's limits.
    pub fn new(gpu: &Gpu, model: M) -> Result<Self, GpuError> {
        let arrays = model.borrow().arrays().ok_or_else(|| {
            atmo::Error::Invalid(
                "molecules with a phase other than Rayleigh's in the higher orders are \
                 drawn on the CPU only; render this model on the CPU"
                    .into(),
            )
        })?;
        let mut data: Vec<[f32; 4]> = Vec::new();
        let mut at = |values: &[[f32; 4]]| {
            let start = data.len() as u32;
            data.extend_from_slice(values);
            start
        };
        let shells: Vec<[f32; 4]> = arrays
            .shell_radius
            .iter()
            .zip(arrays.light_mu_low.iter().zip(&arrays.light_scale))
            .map(|(&r, (&low, &scale))| [r, low, scale, 0.0])
            .collect();
        let rgb: Vec<[f32; 4]> = arrays
            .to_rgb
            .iter()
            .flat_map(|lane| lane.map(|[r, g, b]| [r, g, b, 0.0]))
            .collect();
        let common = ShellParams {
            sun: [0.0; 4],
            grid: [0.0; 4],
            bottom: arrays.bottom_m,
            top: arrays.top_m,
            sun_radius: arrays.sun_radius,
            ground_albedo: arrays.ground_albedo,
            lanes: arrays.lanes as u32,
            multiple: arrays.multiple as u32,
            shells: shells.len() as u32,
            light_entries: arrays.light_map_entries as u32,
            mu_size: arrays.mu_size as u32,
            r_size: arrays.r_size as u32,
            sun_bins: arrays.sun_bins as u32,
            sun_bins_a: arrays.sun_bins_a,
            rayleigh_kind: arrays.rayleigh_phase.kind,
            rayleigh_g: arrays.rayleigh_phase.g,
            mie_kind: arrays.mie_phase.kind,
            mie_g: arrays.mie_phase.g,
            rays_at: 0,
            samples_at: 0,
            rayleigh_at: 0,
            mie_at: 0,
            ground_at: 0,
            shells_at: at(&shells),
            light_at: at(&arrays.light_map),
            irradiance_at: at(&arrays.irradiance),
            transmittance_at: at(&arrays.transmittance),
            moments_at: at(&arrays.moments),
            rgb_at: at(&rgb),
            aerosol_at: at(&arrays.aerosol_table),
            ground_light_at: at(&arrays.ground_irradiance),
            aerosols: !arrays.aerosol_table.is_empty() as u32,
            pad0: 0,
            pad1: 0,
        };
        let mut of = |rays: &RayArrays| {
            let records: Vec<[f32; 4]> = (0..rays.origin_r.len())
                .map(|j| {
                    [
                        f32::from_bits(rays.ray_start[j]),
                        f32::from_bits(rays.ray_start[j + 1]),
                        rays.origin_r[j],
                        rays.ground_distance[j],
                    ]
                })
                .collect();
            let samples: Vec<[f32; 4]> = (0..rays.shell.len())
                .flat_map(|s| {
                    [
                        [
                            f32::from_bits(rays.shell[s]),
                            rays.between[s],
                            rays.altitude[s],
                            rays.distance[s],
                        ],
                        [rays.mu[s], 0.0, 0.0, 0.0],
                    ]
                })
                .collect();
            let g = &rays.grid;
            ShellParams {
                grid: [
                    g.elevation_min as f32,
                    g.elevation_max as f32,
                    g.azimuths as f32,
                    g.elevations as f32,
                ],
                rays_at: at(&records),
                samples_at: at(&samples),
                rayleigh_at: at(&rays.rayleigh),
                mie_at: at(&rays.mie),
                ground_at: at(&rays.ground),
                ..common
            }
        };
        let sky_params = of(&arrays.sky);
        let ground_params = of(&arrays.ground_rays);
        let bytes = bytemuck::cast_slice(&data);
        let buffer = gpu.storage("the sky model's maps", bytes, "shells or directions")?;
        let map = |grid: &DirectionGrid, what: &str| {
            gpu.output(
                what,
                (grid.azimuths * grid.elevations * 12) as u64,
                "directions",
            )
        };
        let module = wgsl::module(gpu, "sky_shells.wgsl")?;
        let to_rgb = SpectrumToRgb::for_atmosphere(model.borrow().atmosphere());
        Ok(GpuSkyModel {
            to_rgb,
            model,
            data: buffer,
            sky_params,
            ground_params,
            sky_map: map(&arrays.sky.grid, "the skylight map")?,
            ground_map: map(&arrays.ground_rays.grid, "the ground map")?,
            sky_grid: arrays.sky.grid,
            ground_grid: arrays.ground_rays.grid,
            shells: gpu.compute_pipeline(&module, "main", None)?,
            uniforms: [
                gpu.uniform("the shell pass (sky)", &sky_params),
                gpu.uniform("the shell pass (ground)", &ground_params),
            ],
            recorded: Mutex::new(None),
        })
    }

    /// The model drawn.
    pub fn model(&self) -> &SkyModel {
        self.model.borrow()
    }

    /// Records the shell pass of both grids for a sun at `sun_elevation` rad.
    pub(super) fn record_maps(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sun_elevation: f64,
    ) {
        *self.recorded.lock().unwrap() = Some(sun_elevation);
        let (sin_s, cos_s) = sun_elevation.sin_cos();
        for (params, map, grid, uniform) in [
            (
                &self.sky_params,
                &self.sky_map,
                &self.sky_grid,
                &self.uniforms[0],
            ),
            (
                &self.ground_params,
                &self.ground_map,
                &self.ground_grid,
                &self.uniforms[1],
            ),
        ] {
            let params = ShellParams {
                sun: [sin_s as f32, cos_s as f32, 0.0, 0.0],
                ..*params
            };
            gpu.queue
                .write_buffer(uniform, 0, bytemuck::bytes_of(&params));
            let group = gpu.bind_group(
                &self.shells.get_bind_group_layout(0),
                &[
                    uniform.as_entire_binding(),
                    self.data.as_entire_binding(),
                    map.as_entire_binding(),
                ],
            );
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.shells);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(
                (grid.azimuths as u32).div_ceil(8),
                (grid.elevations as u32).div_ceil(8),
                1,
            );
        }
    }

    /// Fills the skylight and ground maps for a sun at `sun_elevation` rad, on the GPU
    /// only (what a renderer does each frame); the GPU time, where timed, ms.
    pub fn maps_timed(&self, gpu: &Gpu, sun_elevation: f64) -> Result<Option<f64>, GpuError> {
        gpu.run("the shell pass", |encoder| {
            self.record_maps(gpu, encoder, sun_elevation)
        })
    }

    /// The skylight map and the ground map (linear sRGB, `[elevation][azimuth]`) for a
    /// sun at `sun_elevation` rad, as `SkyModel::skylight_map` and `ground_map` give
    /// them on the CPU, converted to RGB.
    pub fn maps(&self, gpu: &Gpu, sun_elevation: f64) -> Result<[Vec<Vec3>; 2], GpuError> {
        self.maps_timed(gpu, sun_elevation)?;
        let read = |map: &wgpu::Buffer| -> Result<Vec<Vec3>, GpuError> {
            let bytes = gpu.read("the shell maps", map, 0, map.size())?;
            let values: &[f32] = bytemuck::cast_slice(&bytes);
            Ok(values.chunks(3).map(Vec3::from_slice).collect())
        };
        Ok([read(&self.sky_map)?, read(&self.ground_map)?])
    }

    /// Records this frame's skylight and ground maps for `sun` into `encoder` and sets
    /// `pass` to draw them in `view` (seen from the model's altitude, whatever the
    /// camera's height): what a renderer does each frame, before recording
    /// [`SkyPass::draw`]. Nothing is read back. The maps of the sun last recorded are
    /// not recorded again (a still sun costs only the picture pass): submit what is
    /// recorded.
    pub fn prepare(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut SkyPass,
        sun: Sun,
        view: &View,
    ) -> Result<(), GpuError> {
        if *self.recorded.lock().unwrap() != Some(sun.elevation()) {
            self.record_maps(gpu, encoder, sun.elevation());
        }
        let model = self.model();
        let atmosphere = model.atmosphere();
        let mut spectrum = vec![0.0f32; atmosphere.channels()];
        model.sun_radiance(sun.elevation(), &mut spectrum);
        let inputs = FrameInputs {
            sky: &self.sky_map,
            sky_grid: self.sky_grid.clone(),
            ground: Some((&self.ground_map, self.ground_grid.clone())),
            ground_below: -atmo::atmosphere::geometry::horizon_dip(
                atmosphere.bottom_radius_m,
                model.altitude_m(),
            ),
            sun_rgb: self.to_rgb.rgb(&spectrum),
            sun_radius: atmosphere.sun_angular_radius,
        };
        pass.set(gpu, &inputs, sun, view);
        Ok(())
    }

    /// The picture of `view` for `sun`, read back, as
    /// `SkyPicture::new(model, sun).render(view)` on the CPU.
    pub fn render(
        &self,
        gpu: &Gpu,
        pass: &mut SkyPass,
        sun: Sun,
        view: &View,
    ) -> Result<Rendered, GpuError> {
        picture(gpu, pass, view, |encoder, pass| {
            self.prepare(gpu, encoder, pass, sun, view)
        })
    }
}
