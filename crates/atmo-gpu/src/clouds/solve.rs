//! The transfer solve of the orders past the first on the GPU (clouds_solve.wgsl):
//! `atmo::clouds::diffusion` pass for pass, over storage buffers of the solve's grid,
//! so that the draw reads the light toward the eye with nothing read back. The grid and
//! the particles' mean extinction on it ([`SolveGrid`]) are made on the CPU when the
//! particles move (the CPU's own code, so the two solve the same medium); everything
//! the sun changes is made here: the sun's transmittance from the light pass's buffer,
//! the sweeps of the light scattered once (a workgroup a direction, in wavefronts), the
//! diffusion's faces and sources, the conjugate gradients (one workgroup over the grid,
//! whose sums then need no pass of their own: 31,500 cells on the bench's cloud), and
//! the light toward the eye, made again when the eye moves. The sky's light goes
//! through the same passes (its transmittance from the grid's faces swept with the
//! sun's, then a diffusion per channel, each bound to its own segment of the buffers).

use atmo::atmosphere::phase::PhaseFunction;
use atmo::clouds::diffusion::{
    directions, Diffusion, PhaseTables, SolveGrid, DIRECTIONS, LAGS_COLD, LAGS_WARM,
};
use atmo::clouds::SkyLight;

use super::*;

gpu_struct! {
    /// The solve's grid and settings (see clouds_solve.wgsl).
    pub struct SolveParams in "clouds_common.wgsl clouds_lookup.wgsl clouds_solve.wgsl" {
        /// Cell `(0, 0, 0)`'s centre (m); w: the cells' side (m).
        first_centre: [f32; 4],
        /// The eye the light toward the eye is made for (m).
        eye: [f32; 4],
        /// Cells along x, y and z; w: all of them.
        dims: [u32; 4],
        g: f32,
        f: f32,
        d_max: f32,
        limit: u32,
        /// Cells a segment of the fields' buffers; 1 where the sky's light is solved.
        stride: u32,
        sky: u32,
        pad0: u32,
        pad1: u32,
    }
}

/// The solve's passes, made once for a cloud, in [`PASSES`]' order.
pub(super) struct SolvePipelines(Vec<wgpu::ComputePipeline>);

impl SolvePipelines {
    pub(super) fn new(gpu: &Gpu) -> Result<Self, GpuError> {
        let module = wgsl::module(
            gpu,
            "clouds_common.wgsl clouds_lookup.wgsl clouds_solve.wgsl",
        )?;
        let pipelines = PASSES
            .iter()
            .map(|(entry, _, _)| gpu.compute_pipeline(&module, entry, None))
            .collect::<Result<_, _>>()?;
        Ok(SolvePipelines(pipelines))
    }
}

/// A solve's buffers on one grid, its bind groups, and what it was last made for.
pub(super) struct GpuSolve {
    pub(super) settings: Diffusion,
    tables: PhaseTables,
    params: SolveParams,
    params_buffer: wgpu::Buffer,
    /// The light pass's frame the sun's transmittance is read through.
    frame: wgpu::Buffer,
    tables_buffer: wgpu::Buffer,
    /// The light toward the eye, per cell (the draw reads it).
    pub(super) seen: wgpu::Buffer,
    counts: wgpu::Buffer,
    /// Per pass (as [`PASSES`]) its bind groups, one a field's segment for the passes
    /// of one field.
    groups: Vec<Vec<wgpu::BindGroup>>,
    /// Whether the transmittance from the grid's faces has been swept (the particles'
    /// alone: a solve is made again when they move).
    through: bool,
    /// The sun and the sky the solution is of and the light pass it read (none before
    /// the first), and the eye `seen` is for.
    pub(super) sun: Option<(Vec3, BufferFrame, SkyLight)>,
    pub(super) eye: Option<Vec3>,
    cells: u32,
}

/// The solve's passes: each one's entry point in clouds_solve.wgsl, the bindings it
/// reads, and whether it runs on one field bound to its segment of `sources`, `phi`
/// and `fields` (bindings 4, 6 and 8) or sees them whole. Indexed by the constants
/// below, in [`SolvePipelines`] and in a solve's bind groups alike.
const PASSES: [(&str, &[u32], bool); 11] = [
    ("sunlight", &[0, 1, 10, 11], false),
    ("sweep", &[0, 1, 2, 3], false),
    ("scatter", &[0, 1, 2, 3, 4], false),
    ("scatter_sky", &[0, 1, 2, 3, 4], false),
    ("faces_plain", &[0, 1, 5, 6], false),
    ("faces_limited", &[0, 1, 5, 6], false),
    ("right_side", &[0, 1, 4, 5, 7], true),
    ("conjugate_gradients", &[0, 5, 6, 7, 12], true),
    ("moments", &[0, 1, 4, 5, 6, 7], true),
    ("dilate", &[0, 1, 7, 8], true),
    ("toward", &[0, 2, 3, 8, 9], false),
];
const SUNLIGHT: usize = 0;
const SWEEP: usize = 1;
const SCATTER: usize = 2;
const SCATTER_SKY: usize = 3;
/// The plain faces; the limited ones next.
const FACES: usize = 4;
const RIGHT_SIDE: usize = 6;
const CONJUGATE_GRADIENTS: usize = 7;
const MOMENTS: usize = 8;
const DILATE: usize = 9;
const TOWARD: usize = 10;

/// The fields a solve holds: the sun's and the sky's three channels.
const FIELDS: usize = 4;

impl GpuSolve {
    /// The solve of `particles` on the grid `settings` says, for `phase`, reading the
    /// sun's light pass from `cells`: its buffers allocated (refused above the
    /// device's limits, naming `diffusion.cells`).
    pub(super) fn new(
        gpu: &Gpu,
        pipelines: &SolvePipelines,
        particles: &[Particle],
        settings: Diffusion,
        phase: PhaseFunction,
        cells: &wgpu::Buffer,
    ) -> Result<Self, GpuError> {
        let grid = SolveGrid::of(particles, &settings)?;
        let tables = PhaseTables::new(phase);
        let n = grid.cells();
        // Segments a multiple of 64 cells: their offsets the devices' alignment (256).
        let stride = n.next_multiple_of(64);
        let limit = gpu.limits().max_storage_buffer_binding_size;
        gpu.check_limit(
            "the light scattered once along each direction",
            (2 * n * DIRECTIONS * 4) as u64,
            limit,
            "max_storage_buffer_binding_size",
            "diffusion.cells",
        )?;
        let [nx, ny, nz] = grid.dims;
        let params = SolveParams {
            first_centre: [
                grid.first_centre.x,
                grid.first_centre.y,
                grid.first_centre.z,
                grid.cell,
            ],
            eye: [0.0; 4],
            dims: [nx as u32, ny as u32, nz as u32, n as u32],
            g: tables.g(),
            f: tables.f(),
            d_max: nx.max(ny).max(nz) as f32 * grid.cell,
            limit: 4 * n.min(5000) as u32,
            stride: stride as u32,
            sky: 0,
            pad0: 0,
            pad1: 0,
        };
        let medium: Vec<[f32; 4]> = grid
            .sigma_t
            .iter()
            .zip(&grid.sigma_s)
            .map(|(&t, &s)| [t, s, 0.0, 0.0])
            .collect();
        let medium = gpu.storage(
            "the solve's medium",
            bytemuck::cast_slice(&medium),
            "diffusion.cells",
        )?;
        let mut table_values = tables.closure().to_vec();
        table_values.extend_from_slice(tables.lobe());
        table_values.extend(std::iter::repeat_n(0.0, DIRECTIONS));
        table_values.extend(directions().iter().flat_map(|d| d.to_array()));
        table_values.extend(std::iter::repeat_n(0.0, 3 * DIRECTIONS));
        let tables_buffer = gpu.storage(
            "the solve's tables",
            bytemuck::cast_slice(&table_values),
            "diffusion.cells",
        )?;
        let zeros = |what: &str, floats: usize| -> Result<wgpu::Buffer, GpuError> {
            gpu.storage(
                what,
                bytemuck::cast_slice(&vec![0.0f32; floats]),
                "diffusion.cells",
            )
        };
        let once = zeros("the light scattered once", 2 * n * DIRECTIONS)?;
        let sources = zeros("the diffusion's sources", 4 * FIELDS * stride)?;
        let faces = zeros("the diffusion's faces", 4 * n)?;
        let phi = zeros("the fluence", FIELDS * stride)?;
        let work = zeros("the conjugate gradients' vectors", 4 * n)?;
        let fields = zeros("the fluence and flux", 4 * FIELDS * stride)?;
        let seen = zeros("the light toward the eye", 4 * n)?;
        let counts = zeros("the iterations", 1)?;
        let params_buffer = gpu.uniform("the solve's grid", &params);
        let frame = gpu.uniform(
            "the solve's buffer frame",
            &<BufferFrame as bytemuck::Zeroable>::zeroed(),
        );
        let bindings: [&wgpu::Buffer; 13] = [
            &params_buffer,
            &medium,
            &tables_buffer,
            &once,
            &sources,
            &faces,
            &phi,
            &work,
            &fields,
            &seen,
            &frame,
            cells,
            &counts,
        ];
        // A field's segment of a per-field buffer of `bytes` a cell.
        let segment = |binding: u32, field: usize| -> Option<(u64, u64)> {
            let bytes = match binding {
                4 | 8 => 16,
                6 => 4,
                _ => return None,
            };
            let size = (stride * bytes) as u64;
            Some((field as u64 * size, size))
        };
        let groups = pipelines
            .0
            .iter()
            .zip(PASSES)
            .map(|(pipeline, (_, used, per_field))| {
                let fields = if per_field { FIELDS } else { 1 };
                (0..fields)
                    .map(|field| {
                        let entries: Vec<wgpu::BindGroupEntry> = used
                            .iter()
                            .map(|&binding| {
                                let buffer = bindings[binding as usize];
                                let resource = match segment(binding, field) {
                                    Some((offset, size)) if per_field => {
                                        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                            buffer,
                                            offset,
                                            size: std::num::NonZeroU64::new(size),
                                        })
                                    }
                                    _ => buffer.as_entire_binding(),
                                };
                                wgpu::BindGroupEntry { binding, resource }
                            })
                            .collect();
                        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                            label: Some("the transfer solve"),
                            layout: &pipeline.get_bind_group_layout(0),
                            entries: &entries,
                        })
                    })
                    .collect()
            })
            .collect();
        Ok(GpuSolve {
            settings,
            tables,
            params,
            params_buffer,
            frame,
            tables_buffer,
            seen,
            counts,
            groups,
            through: false,
            sun: None,
            eye: None,
            cells: n as u32,
        })
    }

    /// The phase the tables are of.
    pub(super) fn phase(&self) -> PhaseFunction {
        self.tables.phase()
    }

    /// Records the solve for the sun toward `to_sun` through the light pass of `frame`
    /// and for the sky `sky`: from scratch the first time, else from the last solution
    /// (as the CPU's).
    pub(super) fn record_solve(
        &mut self,
        gpu: &Gpu,
        pipelines: &SolvePipelines,
        encoder: &mut wgpu::CommandEncoder,
        frame: &BufferFrame,
        to_sun: Vec3,
        sky: &SkyLight,
    ) {
        let directions = directions();
        let shares = self.tables.shares(&directions, -to_sun.normalize());
        let at = (self.tables.closure().len() + self.tables.lobe().len()) * 4;
        gpu.queue.write_buffer(
            &self.tables_buffer,
            at as u64,
            bytemuck::cast_slice(&shares),
        );
        // The sky's radiance arriving along each direction, the CPU's.
        let radiance: Vec<f32> = sky.around().iter().flat_map(|l| l.to_array()).collect();
        let at = at + DIRECTIONS * 4 * 4;
        gpu.queue.write_buffer(
            &self.tables_buffer,
            at as u64,
            bytemuck::cast_slice(&radiance),
        );
        let with_sky = sky.mean().max_element() > 0.0;
        self.params.sky = with_sky as u32;
        gpu.write_recorded(
            encoder,
            &self.params_buffer,
            0,
            bytemuck::bytes_of(&self.params),
        );
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(frame));
        encoder.clear_buffer(&self.counts, 0, None);
        let warm = self.sun.is_some();
        let mut pass = encoder.begin_compute_pass(&Default::default());
        let cells = groups(gpu, self.cells.div_ceil(GROUP));
        let run = |pass: &mut wgpu::ComputePass, which, field, size| {
            self.dispatch(pass, pipelines, which, field, size)
        };
        // A field's diffusion once its faces are made: right side, conjugate gradients
        // (one workgroup).
        let diffuse = |pass: &mut wgpu::ComputePass, field| {
            run(pass, RIGHT_SIDE, field, cells);
            run(pass, CONJUGATE_GRADIENTS, field, (1, 1));
        };
        run(&mut pass, SUNLIGHT, 0, cells);
        // A workgroup a direction; the sky's as many more, once for particles where they are.
        let sweeps = if with_sky && !self.through { 2 } else { 1 } * DIRECTIONS as u32;
        run(&mut pass, SWEEP, 0, (sweeps, 1));
        run(&mut pass, SCATTER, 0, cells);
        let lags = if warm { LAGS_WARM } else { LAGS_COLD };
        for lag in 0..lags {
            let limited = lag > 0 || warm;
            run(&mut pass, FACES + limited as usize, 0, cells);
            diffuse(&mut pass, 0);
        }
        let fields = if with_sky {
            run(&mut pass, SCATTER_SKY, 0, cells);
            (1..FIELDS).for_each(|field| diffuse(&mut pass, field));
            FIELDS
        } else {
            1
        };
        for field in 0..fields {
            run(&mut pass, MOMENTS, field, cells);
            run(&mut pass, DILATE, field, cells);
        }
        drop(pass);
        self.through |= with_sky;
        self.sun = Some((to_sun, *frame, *sky));
        self.eye = None;
    }

    /// Records the light toward `eye` (after a solve, or where the eye has moved).
    pub(super) fn record_toward(
        &mut self,
        gpu: &Gpu,
        pipelines: &SolvePipelines,
        encoder: &mut wgpu::CommandEncoder,
        eye: Vec3,
    ) {
        // In the encoder's order: two eyes' draws in one submission (two cameras) each
        // read the light toward their own.
        self.params.eye = [eye.x, eye.y, eye.z, 0.0];
        gpu.write_recorded(
            encoder,
            &self.params_buffer,
            0,
            bytemuck::bytes_of(&self.params),
        );
        let cells = groups(gpu, self.cells.div_ceil(GROUP));
        let mut pass = encoder.begin_compute_pass(&Default::default());
        self.dispatch(&mut pass, pipelines, TOWARD, 0, cells);
        drop(pass);
        self.eye = Some(eye);
    }

    /// Records pass `which` (of [`PASSES`]) on `field`'s segment, `size` workgroups
    /// (x, y).
    fn dispatch(
        &self,
        pass: &mut wgpu::ComputePass,
        pipelines: &SolvePipelines,
        which: usize,
        field: usize,
        size: (u32, u32),
    ) {
        pass.set_pipeline(&pipelines.0[which]);
        pass.set_bind_group(0, &self.groups[which][field], &[]);
        pass.dispatch_workgroups(size.0, size.1, 1);
    }

    /// The conjugate-gradient iterations of the last solve (read back).
    pub(super) fn iterations(&self, gpu: &Gpu) -> Result<u32, GpuError> {
        let bytes = gpu.read("the iterations", &self.counts, 0, 4)?;
        Ok(bytemuck::cast_slice::<u8, u32>(&bytes)[0])
    }

    /// The draw's view of the grid: cell `(0, 0, 0)`'s centre and the side, the cells.
    pub(super) fn draw_grid(&self) -> ([f32; 4], [u32; 4]) {
        (self.params.first_centre, self.params.dims)
    }
}
