//! The transfer solve of the orders past the first on the GPU (clouds_solve.wgsl):
//! `atmo::clouds::diffusion` pass for pass, over storage buffers of the solve's grid,
//! so that the draw reads the light toward the eye with nothing read back. The grid and
//! the particles' mean extinction on it ([`SolveGrid`]) are made on the CPU when the
//! particles move (the CPU's own code, so the two solve the same medium); everything
//! the sun changes is made here: the sun's transmittance from the light pass's buffer,
//! the sweeps of the light scattered once (a workgroup a direction, in wavefronts), the
//! diffusion's faces and sources, the conjugate gradients (one workgroup over the grid,
//! whose sums then need no pass of their own: 31,500 cells on the bench's cloud), and
//! the light toward the eye, made again when the eye moves.

use atmo::atmosphere::phase::PhaseFunction;
use atmo::clouds::diffusion::{
    directions, Diffusion, PhaseTables, SolveGrid, DIRECTIONS, LAGS_COLD, LAGS_WARM,
};

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
    }
}

/// The solve's passes, made once for a cloud.
pub(super) struct SolvePipelines {
    sunlight: wgpu::ComputePipeline,
    sweep: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    faces: [wgpu::ComputePipeline; 2],
    right_side: wgpu::ComputePipeline,
    conjugate_gradients: wgpu::ComputePipeline,
    moments: wgpu::ComputePipeline,
    dilate: wgpu::ComputePipeline,
    toward: wgpu::ComputePipeline,
}

impl SolvePipelines {
    pub(super) fn new(gpu: &Gpu) -> Result<Self, GpuError> {
        let module = wgsl::module(
            gpu,
            "clouds_common.wgsl clouds_lookup.wgsl clouds_solve.wgsl",
        )?;
        let make = |entry: &str| gpu.compute_pipeline(&module, entry, None);
        Ok(SolvePipelines {
            sunlight: make("sunlight")?,
            sweep: make("sweep")?,
            scatter: make("scatter")?,
            faces: [make("faces_plain")?, make("faces_limited")?],
            right_side: make("right_side")?,
            conjugate_gradients: make("conjugate_gradients")?,
            moments: make("moments")?,
            dilate: make("dilate")?,
            toward: make("toward")?,
        })
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
    /// Per pass (as [`SolvePipelines`]' order) its bind group.
    groups: Vec<wgpu::BindGroup>,
    /// The sun the solution is of and the light pass it read (none before the first),
    /// and the eye `seen` is for.
    pub(super) sun: Option<(Vec3, BufferFrame)>,
    pub(super) eye: Option<Vec3>,
    cells: u32,
}

/// Which bindings of clouds_solve.wgsl each pass reads, in [`SolvePipelines`]' order.
const BINDINGS: [&[u32]; 10] = [
    &[0, 1, 10, 11],
    &[0, 1, 2, 3],
    &[0, 1, 2, 3, 4],
    &[0, 1, 5, 6],
    &[0, 1, 5, 6],
    &[0, 1, 4, 5, 7],
    &[0, 5, 6, 7, 12],
    &[0, 1, 4, 5, 6, 7],
    &[0, 1, 7, 8],
    &[0, 2, 3, 8, 9],
];

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
        let limit = gpu.limits().max_storage_buffer_binding_size;
        gpu.check_limit(
            "the light scattered once along each direction",
            (n * DIRECTIONS * 4) as u64,
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
        let once = zeros("the light scattered once", n * DIRECTIONS)?;
        let sources = zeros("the diffusion's sources", 4 * n)?;
        let faces = zeros("the diffusion's faces", 4 * n)?;
        let phi = zeros("the fluence", n)?;
        let work = zeros("the conjugate gradients' vectors", 4 * n)?;
        let fields = zeros("the fluence and flux", 4 * n)?;
        let seen = zeros("the light toward the eye", n)?;
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
        let passes = [
            &pipelines.sunlight,
            &pipelines.sweep,
            &pipelines.scatter,
            &pipelines.faces[0],
            &pipelines.faces[1],
            &pipelines.right_side,
            &pipelines.conjugate_gradients,
            &pipelines.moments,
            &pipelines.dilate,
            &pipelines.toward,
        ];
        let groups = passes
            .iter()
            .zip(BINDINGS)
            .map(|(pipeline, used)| {
                let entries: Vec<wgpu::BindGroupEntry> = used
                    .iter()
                    .map(|&binding| wgpu::BindGroupEntry {
                        binding,
                        resource: bindings[binding as usize].as_entire_binding(),
                    })
                    .collect();
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("the transfer solve"),
                    layout: &pipeline.get_bind_group_layout(0),
                    entries: &entries,
                })
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
            sun: None,
            eye: None,
            cells: n as u32,
        })
    }

    /// The phase the tables are of.
    pub(super) fn phase(&self) -> PhaseFunction {
        self.tables.phase()
    }

    /// Records the solve for the sun toward `to_sun` through the light pass of `frame`:
    /// from scratch the first time, else from the last solution (as the CPU's).
    pub(super) fn record_solve(
        &mut self,
        gpu: &Gpu,
        pipelines: &SolvePipelines,
        encoder: &mut wgpu::CommandEncoder,
        frame: &BufferFrame,
        to_sun: Vec3,
    ) {
        let shares = self.tables.shares(&directions(), -to_sun.normalize());
        let at = (self.tables.closure().len() + self.tables.lobe().len()) * 4;
        gpu.queue.write_buffer(
            &self.tables_buffer,
            at as u64,
            bytemuck::cast_slice(&shares),
        );
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(frame));
        encoder.clear_buffer(&self.counts, 0, None);
        let warm = self.sun.is_some();
        let mut pass = encoder.begin_compute_pass(&Default::default());
        let cells = groups(gpu, self.cells.div_ceil(GROUP));
        let wide = |pass: &mut wgpu::ComputePass, pipeline, group: usize| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.groups[group], &[]);
            pass.dispatch_workgroups(cells.0, cells.1, 1);
        };
        wide(&mut pass, &pipelines.sunlight, 0);
        pass.set_pipeline(&pipelines.sweep);
        pass.set_bind_group(0, &self.groups[1], &[]);
        pass.dispatch_workgroups(DIRECTIONS as u32, 1, 1);
        wide(&mut pass, &pipelines.scatter, 2);
        let lags = if warm { LAGS_WARM } else { LAGS_COLD };
        for lag in 0..lags {
            let limited = lag > 0 || warm;
            wide(
                &mut pass,
                &pipelines.faces[limited as usize],
                3 + limited as usize,
            );
            wide(&mut pass, &pipelines.right_side, 5);
            pass.set_pipeline(&pipelines.conjugate_gradients);
            pass.set_bind_group(0, &self.groups[6], &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        wide(&mut pass, &pipelines.moments, 7);
        wide(&mut pass, &pipelines.dilate, 8);
        self.sun = Some((to_sun, *frame));
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
        self.params.eye = [eye.x, eye.y, eye.z, 0.0];
        gpu.queue
            .write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        let cells = groups(gpu, self.cells.div_ceil(GROUP));
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipelines.toward);
        pass.set_bind_group(0, &self.groups[9], &[]);
        pass.dispatch_workgroups(cells.0, cells.1, 1);
        self.eye = Some(eye);
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
