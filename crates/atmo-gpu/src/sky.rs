//! The sky from the skylight table on the GPU (sky 4.2): the table's factors live in
//! storage buffers; per frame, the CPU interpolates the few hundred `t_k` (sky (17)),
//! one compute pass sums the terms of every view direction into the skylight map, and
//! a second draws the picture (perspective or fisheye) from it, as
//! `atmo::sky::frame::SkyPicture` does on the CPU.

use atmo::image::Frame;
use atmo::sky::frame::{sun_disc_rgb, GridLookup, PixelBasis, View};
use atmo::sky::table::SkylightTable;
use atmo::sky::Sun;
use glam::Vec3;

use crate::{gpu_struct, Gpu, GpuError, Rendered};

gpu_struct! {
    /// The map pass's sizes.
    pub struct SkyMapParams in "sky_map.wgsl" {
        /// Rows: 3 channels x view directions.
        rows: u32,
        /// Terms stored (`t_k` per frame).
        terms: u32,
        /// View directions per channel.
        directions: u32,
        pad: u32,
    }
}

gpu_struct! {
    /// The frame pass's camera, sun and map lookup (see sky_frame.wgsl).
    pub struct SkyFrameParams in "sky_frame.wgsl" {
        origin: [f32; 4],
        right: [f32; 4],
        up: [f32; 4],
        sun_direction: [f32; 4],
        sun_rgb: [f32; 4],
        sun_horizontal: [f32; 4],
        lookup: [f32; 4],
        y_last: f32,
        ground_below: f32,
        radius: f32,
        fisheye: u32,
        width: u32,
        height: u32,
        azimuths: u32,
        sun_radius: f32,
        pixel: f32,
        pad0: u32,
        pad1: u32,
        pad2: u32,
    }
}

/// A skylight table uploaded, with its two pipelines.
pub struct GpuSkyTable<'a> {
    table: &'a SkylightTable,
    params: SkyMapParams,
    s: wgpu::Buffer,
    order: wgpu::Buffer,
    used: wgpu::Buffer,
    /// The skylight map, written by the map pass, read by the frame pass.
    map: wgpu::Buffer,
    map_pass: wgpu::ComputePipeline,
    frame_pass: wgpu::ComputePipeline,
}

impl<'a> GpuSkyTable<'a> {
    /// Uploads `table`'s factors (refused above the device's buffer limits).
    pub fn new(gpu: &Gpu, table: &'a SkylightTable) -> Result<Self, GpuError> {
        let f = table.factors();
        let setting = "the table's directions or epsilon";
        let s = gpu.storage("the table's s_k", bytemuck::cast_slice(f.s), setting)?;
        let order = gpu.storage(
            "the table's row order",
            bytemuck::cast_slice(f.order),
            setting,
        )?;
        let used = gpu.storage(
            "the table's term use",
            bytemuck::cast_slice(f.used),
            setting,
        )?;
        let map_bytes = (f.directions * 3 * 4) as u64;
        let map = output(gpu, "the skylight map", map_bytes, setting)?;
        let map_module = gpu.shader("sky_map.wgsl", include_str!("../shaders/sky_map.wgsl"))?;
        let frame_module =
            gpu.shader("sky_frame.wgsl", include_str!("../shaders/sky_frame.wgsl"))?;
        Ok(GpuSkyTable {
            table,
            params: SkyMapParams {
                rows: f.order.len() as u32,
                terms: f.used.len() as u32,
                directions: f.directions as u32,
                pad: 0,
            },
            s,
            order,
            used,
            map,
            map_pass: gpu.compute_pipeline(&map_module, "main", None)?,
            frame_pass: gpu.compute_pipeline(&frame_module, "main", None)?,
        })
    }

    /// Records the map pass for a sun at `sun_elevation` rad seen from `altitude_m`.
    fn record_map(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        coefficients: &wgpu::Buffer,
        params: &wgpu::Buffer,
    ) {
        let group = gpu.bind_group(
            &self.map_pass.get_bind_group_layout(0),
            &[
                params.as_entire_binding(),
                self.s.as_entire_binding(),
                self.order.as_entire_binding(),
                self.used.as_entire_binding(),
                coefficients.as_entire_binding(),
                self.map.as_entire_binding(),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.map_pass);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(self.params.rows.div_ceil(64), 1, 1);
    }

    /// The per-frame inputs of the map pass: `t_k` and the sizes.
    fn map_inputs(
        &self,
        gpu: &Gpu,
        sun_elevation: f64,
        altitude_m: f64,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
        let coefficients = self.table.coefficients(sun_elevation, altitude_m)?;
        Ok((
            gpu.storage("t_k", bytemuck::cast_slice(&coefficients), "epsilon")?,
            gpu.uniform("sky map", &self.params),
        ))
    }

    /// The skylight map (linear sRGB, `[elevation][azimuth]` over the table's grid), as
    /// `SkylightTable::map` gives it on the CPU, and the GPU time of its pass (ms) where
    /// the adapter has timestamps.
    pub fn map(
        &self,
        gpu: &Gpu,
        sun_elevation: f64,
        altitude_m: f64,
    ) -> Result<(Vec<Vec3>, Option<f64>), GpuError> {
        let (coefficients, params) = self.map_inputs(gpu, sun_elevation, altitude_m)?;
        let gpu_ms = gpu.run("the skylight map", |encoder, _| {
            self.record_map(gpu, encoder, &coefficients, &params)
        })?;
        let bytes = gpu.read("the skylight map", &self.map, 0, self.map.size())?;
        let values: &[f32] = bytemuck::cast_slice(&bytes);
        Ok((values.chunks(3).map(Vec3::from_slice).collect(), gpu_ms))
    }

    /// The picture of `view` for `sun` seen from `altitude_m`: map pass and frame pass
    /// in one submission, as `SkyPicture::from_table(..).render(view)` on the CPU.
    pub fn render(
        &self,
        gpu: &Gpu,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<Rendered, GpuError> {
        let pixels = view.width as u64 * view.height as u64;
        let out = output(gpu, "the sky frame", pixels * 16, "the image size")?;
        let (coefficients, map_params) = self.map_inputs(gpu, sun.elevation, altitude_m)?;
        let params = gpu.uniform("sky frame", &self.frame_params(sun, altitude_m, view));
        let group = gpu.bind_group(
            &self.frame_pass.get_bind_group_layout(0),
            &[
                params.as_entire_binding(),
                self.map.as_entire_binding(),
                out.as_entire_binding(),
            ],
        );
        let gpu_ms = gpu.run("the sky frame", |encoder, _| {
            self.record_map(gpu, encoder, &coefficients, &map_params);
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.frame_pass);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(view.width.div_ceil(8), view.height.div_ceil(8), 1);
        })?;
        let bytes = gpu.read("the sky frame", &out, 0, pixels * 16)?;
        Ok(Rendered {
            frame: frame_of(view.width, view.height, &bytes),
            gpu_ms,
        })
    }

    fn frame_params(&self, sun: Sun, altitude_m: f64, view: &View) -> SkyFrameParams {
        let atmosphere = self.table.atmosphere();
        let grid = self.table.grid(altitude_m);
        let lookup = GridLookup::new(&grid);
        let direction = atmo::sky::frame::direction_of(sun.azimuth, sun.elevation).as_vec3();
        let rgb = sun_disc_rgb(atmosphere, altitude_m, sun.elevation);
        let (sin_a, cos_a) = sun.azimuth.sin_cos();
        let v4 = |v: Vec3| [v.x, v.y, v.z, 0.0];
        let basis = view.projection.pixel_basis(view.width, view.height);
        let (sun_radius, pixel) = (atmosphere.sun_angular_radius as f32, basis.pixel_angle());
        let mut p = SkyFrameParams {
            origin: [0.0; 4],
            right: [0.0; 4],
            up: [0.0; 4],
            sun_direction: [
                direction.x,
                direction.y,
                direction.z,
                (sun_radius + pixel).cos(),
            ],
            sun_rgb: [rgb[0], rgb[1], rgb[2], view.sun_disc as u32 as f32],
            sun_horizontal: [sin_a as f32, cos_a as f32, 0.0, 0.0],
            lookup: [lookup.x_scale, lookup.y_min, lookup.y_scale, lookup.x_last],
            y_last: lookup.y_last,
            ground_below: grid.elevation_min as f32,
            radius: 1.0,
            fisheye: 0,
            width: view.width,
            height: view.height,
            azimuths: lookup.azimuths as u32,
            sun_radius,
            pixel,
            pad0: 0,
            pad1: 0,
            pad2: 0,
        };
        match basis {
            PixelBasis::Perspective { origin, right, up } => {
                (p.origin, p.right, p.up) = (v4(origin), v4(right), v4(up));
            }
            PixelBasis::Fisheye { centre, radius } => {
                p.fisheye = 1;
                p.radius = radius;
                p.sun_horizontal[2] = centre.x;
                p.sun_horizontal[3] = centre.y;
            }
        }
        p
    }
}

/// A storage buffer the GPU writes and the CPU reads back, checked against the limits.
pub(crate) fn output(
    gpu: &Gpu,
    what: &str,
    bytes: u64,
    setting: &str,
) -> Result<wgpu::Buffer, GpuError> {
    let limits = gpu.limits();
    gpu.check_limit(
        what,
        bytes,
        limits.max_storage_buffer_binding_size,
        "max_storage_buffer_binding_size",
        setting,
    )?;
    Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size: bytes.max(4),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    }))
}

/// A frame of `width` x `height` from RGBA f32 pixels, alpha dropped.
pub(crate) fn frame_of(width: u32, height: u32, bytes: &[u8]) -> Frame {
    let values: &[f32] = bytemuck::cast_slice(bytes);
    let mut frame = Frame::new(width, height);
    for (pixel, v) in frame.pixels.iter_mut().zip(values.chunks(4)) {
        *pixel = Vec3::new(v[0], v[1], v[2]);
    }
    frame
}
