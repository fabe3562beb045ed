//! The sky from the skylight table on the GPU (sky 4.2): per frame the CPU
//! interpolates the `t_k` and one compute pass sums the terms into the map.

use std::sync::Mutex;

use super::*;

/// A skylight table uploaded, with its map pass; `T` is the table borrowed
/// (`&SkylightTable`) or owned (`SkylightTable`, `Arc<SkylightTable>`).
pub struct GpuSkyTable<T: Borrow<SkylightTable>> {
    pub(super) table: T,
    pub(super) s: wgpu::Buffer,
    pub(super) order: wgpu::Buffer,
    pub(super) used: wgpu::Buffer,
    /// `t_k`, written per frame.
    pub(super) coefficients: wgpu::Buffer,
    /// The map pass's sizes.
    pub(super) params: wgpu::Buffer,
    /// The skylight map, written by the map pass, read by the picture pass.
    pub(super) map: wgpu::Buffer,
    pub(super) rows: u32,
    pub(super) map_pass: wgpu::ComputePipeline,
    /// The sun elevation and altitude whose map was last recorded: `prepare` records it
    /// again only for another.
    pub(super) recorded: Mutex<Option<(f64, f64)>>,
}

impl<T: Borrow<SkylightTable>> GpuSkyTable<T> {
    /// Uploads `table`'s factors (refused above the device's buffer limits).
    pub fn new(gpu: &Gpu, table: T) -> Result<Self, GpuError> {
        let f = table.borrow().factors();
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
        let coefficients = gpu.storage(
            "t_k",
            bytemuck::cast_slice(&vec![0f32; f.used.len()]),
            setting,
        )?;
        let map_bytes = (f.directions * 3 * 4) as u64;
        let map = gpu.output("the skylight map", map_bytes, setting)?;
        let map_module = wgsl::module(gpu, "sky_map.wgsl")?;
        let params = SkyMapParams {
            rows: f.order.len() as u32,
            terms: f.used.len() as u32,
            directions: f.directions as u32,
            pad: 0,
        };
        Ok(GpuSkyTable {
            table,
            s,
            order,
            used,
            coefficients,
            params: gpu.uniform("sky map", &params),
            map,
            rows: params.rows,
            map_pass: gpu.compute_pipeline(&map_module, "main", None)?,
            recorded: Mutex::new(None),
        })
    }

    /// The table drawn.
    pub fn table(&self) -> &SkylightTable {
        self.table.borrow()
    }

    /// Writes `t_k` for a sun at `sun_elevation` rad seen from `altitude_m` (refused
    /// outside the table's ranges) and records the map pass.
    pub(super) fn record_map(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        sun_elevation: f64,
        altitude_m: f64,
    ) -> Result<(), GpuError> {
        let coefficients = self.table().coefficients(sun_elevation, altitude_m)?;
        *self.recorded.lock().unwrap() = Some((sun_elevation, altitude_m));
        gpu.queue
            .write_buffer(&self.coefficients, 0, bytemuck::cast_slice(&coefficients));
        let group = gpu.bind_group(
            &self.map_pass.get_bind_group_layout(0),
            &[
                self.params.as_entire_binding(),
                self.s.as_entire_binding(),
                self.order.as_entire_binding(),
                self.used.as_entire_binding(),
                self.coefficients.as_entire_binding(),
                self.map.as_entire_binding(),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.map_pass);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(self.rows.div_ceil(64), 1, 1);
        Ok(())
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
        let mut recorded = Ok(());
        let gpu_ms = gpu.run("the skylight map", |encoder| {
            recorded = self.record_map(gpu, encoder, sun_elevation, altitude_m);
        })?;
        recorded?;
        let bytes = gpu.read("the skylight map", &self.map, 0, self.map.size())?;
        let values: &[f32] = bytemuck::cast_slice(&bytes);
        Ok((values.chunks(3).map(Vec3::from_slice).collect(), gpu_ms))
    }

    /// Records this frame's skylight map for `sun` seen from `altitude_m` into
    /// `encoder` and sets `pass` to draw it in `view`: what a renderer does each frame,
    /// before recording [`SkyPass::draw`] in a render pass of the same encoder (or a
    /// later one). Nothing is read back. The map of the sun and altitude last recorded
    /// is not recorded again: submit what is recorded.
    pub fn prepare(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        pass: &mut SkyPass,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<(), GpuError> {
        if *self.recorded.lock().unwrap() != Some((sun.elevation(), altitude_m)) {
            self.record_map(gpu, encoder, sun.elevation(), altitude_m)?;
        }
        let atmosphere = self.table().atmosphere();
        let grid = self.table().grid(altitude_m);
        let inputs = FrameInputs {
            sky: &self.map,
            ground_below: grid.elevation_min,
            sky_grid: grid,
            ground: None,
            sun_rgb: sun_disc_rgb(atmosphere, altitude_m, sun.elevation()),
            sun_radius: atmosphere.sun_angular_radius,
        };
        pass.set(gpu, &inputs, sun, view);
        Ok(())
    }

    /// The picture of `view` for `sun` seen from `altitude_m`, read back: map pass and
    /// picture pass in one submission, as `SkyPicture::from_table(..).render(view)` on
    /// the CPU.
    pub fn render(
        &self,
        gpu: &Gpu,
        pass: &mut SkyPass,
        sun: Sun,
        altitude_m: f64,
        view: &View,
    ) -> Result<Rendered, GpuError> {
        picture(gpu, pass, view, |encoder, pass| {
            self.prepare(gpu, encoder, pass, sun, altitude_m, view)
        })
    }
}
