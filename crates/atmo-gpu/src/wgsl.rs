//! How the shaders are put together, and what they share with the Rust.
//!
//! Every pass's source is composed the same way, by [`source`]: a prelude of constants
//! generated from the Rust (the kinds of phase function, object, falloff and gobo), then
//! `functions.wgsl` (the WGSL twins of `atmo::fast`, `erf` and the phase functions),
//! then the pass's own files in order. No text of a file is edited on the way: a pass
//! that needs other declarations takes another file.

use atmo::atmosphere::PhaseFunction;
use atmo::clouds::buffer::FOOTPRINT;
use atmo::clouds::diffusion;
use atmo::clouds::particles::{EMISSION_WEIGHTS, FADE_SCALE, GAUSS_LEGENDRE};
use atmo::clouds::render::OPAQUE;
use atmo::clouds::transfer;
use atmo::shafts::planes::{ANGLE_STEP, MAX_ANGLE_SAMPLES, NEAR_LAMP};
use atmo::shafts::shadow_map::RECEIVER_BIAS;
use atmo::sky::shells::export;

use crate::{Gpu, GpuError};

/// Declares `u32` codes once for the Rust and, through [`prelude`], for WGSL.
macro_rules! shared_codes {
    ($($(#[$meta:meta])* $name:ident = $value:expr;)*) => {
        $($(#[$meta])* pub const $name: u32 = $value;)*
        /// Every code, by the name WGSL knows it by.
        const SHARED: &[(&str, u32)] = &[$((stringify!($name), $value)),*];
    };
}

shared_codes! {
    /// An infinite plane (atmo::geometry::Shape::Plane) in the shafts' geometry buffer.
    OBJECT_PLANE = 0;
    /// A parallelogram.
    OBJECT_RECT = 1;
    /// A sphere.
    OBJECT_SPHERE = 2;
    /// An axis-aligned box.
    OBJECT_BOX = 3;
    /// A triangle mesh with its BVH.
    OBJECT_MESH = 4;
    /// Or-ed into an object's kind: it casts no shadow (a moving head's body).
    OBJECT_NO_SHADOW = 128;
    /// A spotlight's soft edge falls linearly with the angle.
    FALLOFF_LINEAR = 0;
    /// A spotlight's soft edge falls as a smoothstep.
    FALLOFF_SMOOTH = 1;
    /// A spotlight's profile is measured (a photometric file): its light map holds it.
    FALLOFF_MEASURED = 2;
    /// No gobo.
    GOBO_NONE = 0;
    /// A gobo sampled at the nearest texel.
    GOBO_NEAREST = 1;
    /// A gobo sampled bilinearly.
    GOBO_BILINEAR = 2;
    /// atmo::image::ToneMap::Clamp.
    TONE_CLAMP = 0;
    /// atmo::image::ToneMap::Exponential.
    TONE_EXPONENTIAL = 1;
    /// atmo::image::ToneMap::Aces.
    TONE_ACES = 2;
}

/// The shader files, by name, as compiled into the crate.
const FILES: &[(&str, &str)] = &[
    ("functions.wgsl", include_str!("../shaders/functions.wgsl")),
    ("screen.wgsl", include_str!("../shaders/screen.wgsl")),
    ("display.wgsl", include_str!("../shaders/display.wgsl")),
    ("sky_map.wgsl", include_str!("../shaders/sky_map.wgsl")),
    ("sky_frame.wgsl", include_str!("../shaders/sky_frame.wgsl")),
    (
        "sky_shells.wgsl",
        include_str!("../shaders/sky_shells.wgsl"),
    ),
    (
        "clouds_common.wgsl",
        include_str!("../shaders/clouds_common.wgsl"),
    ),
    (
        "clouds_light.wgsl",
        include_str!("../shaders/clouds_light.wgsl"),
    ),
    (
        "clouds_lookup.wgsl",
        include_str!("../shaders/clouds_lookup.wgsl"),
    ),
    (
        "clouds_sky_depths.wgsl",
        include_str!("../shaders/clouds_sky_depths.wgsl"),
    ),
    (
        "clouds_prefix.wgsl",
        include_str!("../shaders/clouds_prefix.wgsl"),
    ),
    (
        "clouds_draw.wgsl",
        include_str!("../shaders/clouds_draw.wgsl"),
    ),
    (
        "clouds_solve.wgsl",
        include_str!("../shaders/clouds_solve.wgsl"),
    ),
    (
        "shafts_common.wgsl",
        include_str!("../shaders/shafts_common.wgsl"),
    ),
    (
        "shafts_objects.wgsl",
        include_str!("../shaders/shafts_objects.wgsl"),
    ),
    (
        "shafts_spotlight.wgsl",
        include_str!("../shaders/shafts_spotlight.wgsl"),
    ),
    (
        "shafts_tables.wgsl",
        include_str!("../shaders/shafts_tables.wgsl"),
    ),
    (
        "shafts_sampling.wgsl",
        include_str!("../shaders/shafts_sampling.wgsl"),
    ),
    (
        "shafts_writable.wgsl",
        include_str!("../shaders/shafts_writable.wgsl"),
    ),
    (
        "shafts_readable.wgsl",
        include_str!("../shaders/shafts_readable.wgsl"),
    ),
    (
        "shafts_shadow.wgsl",
        include_str!("../shaders/shafts_shadow.wgsl"),
    ),
    (
        "shafts_prepare.wgsl",
        include_str!("../shaders/shafts_prepare.wgsl"),
    ),
    (
        "shafts_surface.wgsl",
        include_str!("../shaders/shafts_surface.wgsl"),
    ),
    (
        "clouds_composite.wgsl",
        include_str!("../shaders/clouds_composite.wgsl"),
    ),
    (
        "shafts_frame.wgsl",
        include_str!("../shaders/shafts_frame.wgsl"),
    ),
    (
        "shafts_compute.wgsl",
        include_str!("../shaders/shafts_compute.wgsl"),
    ),
    (
        "shafts_planes.wgsl",
        include_str!("../shaders/shafts_planes.wgsl"),
    ),
    (
        "shafts_composite.wgsl",
        include_str!("../shaders/shafts_composite.wgsl"),
    ),
    (
        "shafts_attenuation.wgsl",
        include_str!("../shaders/shafts_attenuation.wgsl"),
    ),
];

/// The length of the transfer table's node arrays in WGSL: its longest axis's.
const TRANSFER_NODES: usize = 6;
const _: () = assert!(
    transfer::THICKNESS.len() <= TRANSFER_NODES
        && transfer::SUN.len() <= TRANSFER_NODES
        && transfer::OUT.len() <= TRANSFER_NODES
        && transfer::COSINE.len() <= TRANSFER_NODES
        && transfer::EYE.len() <= TRANSFER_NODES
);

/// The constants WGSL shares with the Rust, generated: `const PHASE_RAYLEIGH: u32 = 0u;`
/// and the rest of [`PhaseFunction::CODES`], this module's codes, the sky model's
/// `MOMENTS`, `TABLE_MU`, `TABLE_PHI` and `MAX_LANES`, the clouds' `FOOTPRINT`,
/// `FADE_SCALE`, `EMISSION_FRACTIONS`, `EMISSION_WEIGHTS` and `OPAQUE`, their transfer
/// solve's `DIRECTIONS`, `CLOSURE_STEPS`, `CLOSURE_MAX`, `LOBE_STEPS`, `STREAMING`,
/// `THIN` and `TOLERANCE`, and their
/// transfer table's nodes (`TRANSFER_THICKNESS` and its `TRANSFER_THICKNESS_COUNT`, ..., padded to
/// `TRANSFER_NODES`), the shadow maps' `RECEIVER_BIAS`, and the shafts' near-lamp
/// slabs' `NEAR_LAMP`, `ANGLE_STEP` and `MAX_ANGLE_SAMPLES`.
pub fn prelude() -> String {
    let phases = PhaseFunction::CODES
        .iter()
        .map(|(name, code)| (format!("PHASE_{name}"), *code));
    let sizes = [
        ("MOMENTS", export::MOMENTS as u32),
        ("TABLE_MU", export::TABLE_MU as u32),
        ("TABLE_PHI", export::TABLE_PHI as u32),
        ("MAX_LANES", export::MAX_LANES as u32),
        ("DIRECTIONS", diffusion::DIRECTIONS as u32),
        ("CLOSURE_STEPS", diffusion::CLOSURE_STEPS as u32),
        ("LOBE_STEPS", diffusion::LOBE_STEPS as u32),
    ];
    let shared = SHARED.iter().chain(&sizes);
    let shared = shared.map(|(name, code)| (name.to_string(), *code));
    let mut out = String::from("// Generated by atmo_gpu::wgsl::prelude from the Rust.\n");
    for (name, code) in phases.chain(shared) {
        out.push_str(&format!("const {name}: u32 = {code}u;\n"));
    }
    // How far across the light a particle's footprint reaches, in standard deviations,
    // and the scale of a faded billboard's column.
    out.push_str(&format!("const FOOTPRINT: f32 = {:?};\n", FOOTPRINT));
    out.push_str(&format!("const FADE_SCALE: f32 = {:?};\n", FADE_SCALE));
    // A blob's emission nodes: their shares of its absorbed fraction and their weights.
    for (name, values) in [
        ("EMISSION_FRACTIONS", GAUSS_LEGENDRE),
        ("EMISSION_WEIGHTS", EMISSION_WEIGHTS),
    ] {
        let [a, b, c] = values;
        out.push_str(&format!("const {name} = vec3<f32>({a:?}, {b:?}, {c:?});\n"));
    }
    // The clouds' transfer solve: its closure's range, streaming limit, least optical
    // depth of a cloud cell and conjugate gradients' tolerance.
    for (name, value) in [
        ("CLOSURE_MAX", diffusion::CLOSURE_MAX),
        ("STREAMING", diffusion::STREAMING),
        ("THIN", diffusion::THIN),
        ("TOLERANCE", diffusion::TOLERANCE as f32),
    ] {
        out.push_str(&format!("const {name}: f32 = {value:?};\n"));
    }
    // The transmittance below which a cloud's pixel counts as opaque.
    out.push_str(&format!("const OPAQUE: f32 = {:?};\n", OPAQUE));
    // The clouds' transfer table's nodes, each axis padded with its last node.
    out.push_str(&format!("const TRANSFER_NODES: u32 = {TRANSFER_NODES}u;\n"));
    for (name, nodes) in [
        ("THICKNESS", &transfer::THICKNESS[..]),
        ("SUN", &transfer::SUN),
        ("OUT", &transfer::OUT),
        ("COSINE", &transfer::COSINE),
        ("EYE", &transfer::EYE),
    ] {
        let padded: Vec<String> = (0..TRANSFER_NODES)
            .map(|k| format!("{:?}", nodes[k.min(nodes.len() - 1)]))
            .collect();
        out.push_str(&format!(
            "const TRANSFER_{name}: array<f32, {TRANSFER_NODES}> = array<f32, {TRANSFER_NODES}>({});\n\
             const TRANSFER_{name}_COUNT: u32 = {}u;\n",
            padded.join(", "),
            nodes.len()
        ));
    }
    // How much nearer than a receiver's plane a shadow map's surface must be.
    out.push_str(&format!(
        "const RECEIVER_BIAS: f32 = {:?};\n",
        RECEIVER_BIAS
    ));
    // Which slabs of the shafts' planes pass near the lamp, and their angle spacing.
    for (name, value) in [
        ("NEAR_LAMP", NEAR_LAMP),
        ("ANGLE_STEP", ANGLE_STEP),
        ("MAX_ANGLE_SAMPLES", MAX_ANGLE_SAMPLES),
    ] {
        out.push_str(&format!("const {name}: f32 = {value:?};\n"));
    }
    out
}

/// The source of a pass made of `files` (names under `shaders/`, separated by spaces):
/// the [`prelude`], `functions.wgsl`, then the files in order.
///
/// # Panics
/// For a name that is not one of the crate's shader files: a mistake in this crate,
/// which every pipeline's test would show.
pub fn source(files: &str) -> String {
    let mut out = prelude();
    for name in std::iter::once("functions.wgsl").chain(files.split_whitespace()) {
        let (_, text) = FILES
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("no shader file {name}"));
        out.push('\n');
        out.push_str(text);
    }
    out
}

/// The module of a pass made of `files` (see [`source`]), named after its last file.
pub(crate) fn module(gpu: &Gpu, files: &str) -> Result<wgpu::ShaderModule, GpuError> {
    let name = files.split_whitespace().last().unwrap_or(files);
    gpu.shader(name, &source(files))
}

/// Evaluates the WGSL `expression` of `v: vec4<f32>` (which may call anything in
/// `functions.wgsl`, e.g. `fast_acos(v.x)`) for each of `inputs` on the GPU: how the
/// twin tests hold each WGSL function to its Rust original.
pub fn evaluate(gpu: &Gpu, expression: &str, inputs: &[[f32; 4]]) -> Result<Vec<f32>, GpuError> {
    let harness = format!(
        "{}
@group(0) @binding(0) var<storage, read> inputs: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> outputs: array<f32>;

@compute @workgroup_size(64)
fn evaluate(@builtin(global_invocation_id) id: vec3<u32>) {{
    if id.x >= arrayLength(&inputs) {{
        return;
    }}
    let v = inputs[id.x];
    outputs[id.x] = {expression};
}}
",
        source("")
    );
    let module = gpu.shader("a twin test", &harness)?;
    let pipeline = gpu.compute_pipeline(&module, "evaluate", None)?;
    let input = gpu.storage("the inputs", bytemuck::cast_slice(inputs), "the inputs")?;
    let bytes = inputs.len() as u64 * 4;
    let output = gpu.output("the outputs", bytes, "the inputs")?;
    let group = gpu.bind_group(
        &pipeline.get_bind_group_layout(0),
        &[input.as_entire_binding(), output.as_entire_binding()],
    );
    gpu.run("a twin test", |encoder| {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((inputs.len() as u32).div_ceil(64), 1, 1);
    })?;
    let values = gpu.read("the outputs", &output, 0, bytes)?;
    Ok(bytemuck::cast_slice(&values).to_vec())
}
