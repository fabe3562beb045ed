// The light pass of clouds 3.3, order-independent: every particle adds log G (7) to
// the cells where its shadow starts (Splat::Whole, the paper's shadow polygons) or its
// optical depth split between the cells it crosses (Splat::Pieces), by integer atomics;
// clouds_prefix.wgsl then sums each column along the light. The same arithmetic as
// atmo::clouds::buffer's Stamp, one workgroup per particle, its threads over the
// columns of the particle's footprint.

@group(0) @binding(0) var<uniform> frame: BufferFrame;
@group(0) @binding(1) var<storage, read> particles: array<GpuParticle>;
// Fixed-point ln Gamma increments, [x][z][y].
@group(0) @binding(2) var<storage, read_write> cells: array<atomic<i32>>;

// FOOTPRINT, how far across the light a footprint reaches in standard deviations,
// comes from the prelude (atmo::clouds::buffer::FOOTPRINT).

// Cells along y whose shares are kept in workgroup memory; longer runs recompute.
const CACHED: u32 = 1024u;
var<workgroup> shares: array<f32, 1024>;

fn centre(axis: u32, i: u32) -> f32 {
    return frame.min[axis] + (f32(i) + 0.5) * frame.voxel[axis];
}

// Voxel index range [first, last) along `axis` whose centres lie within [a, b].
fn centres_within(axis: u32, a: f32, b: f32) -> vec2<u32> {
    let n = f32(frame.resolution);
    let first = clamp(ceil((a - frame.min[axis]) / frame.voxel[axis] - 0.5), 0.0, n);
    let last = clamp(floor((b - frame.min[axis]) / frame.voxel[axis] - 0.5) + 1.0, 0.0, n);
    return vec2<u32>(u32(first), u32(last));
}

// Share of the particle's depth in cell j (Pieces): erf between neighbouring centres.
fn share(j: u32, y: vec2<u32>, cy: f32, k: f32) -> f32 {
    var above = 1.0;
    if j != y.y {
        above = erf((centre(1u, j) - cy) * k);
    }
    var below = -1.0;
    if j != y.x {
        below = erf((centre(1u, j - 1u) - cy) * k);
    }
    return 0.5 * (above - below);
}

fn add(ix: u32, iy: u32, iz: u32, value: f32) {
    let n = frame.resolution;
    atomicAdd(&cells[(ix * n + iz) * n + iy], i32(round(value * FIXED_SCALE)));
}

@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let index = group.y * groups.x + group.x;
    // Uniform per workgroup: every thread returns or none does (barrier below).
    if index >= frame.particles {
        return;
    }
    let p = particles[index];
    let radius = p.position_radius.w;
    let s = radius / 3.0;
    let c = to_buffer(frame, p.position_radius.xyz);
    let reach = FOOTPRINT * s;
    let inv_2s2 = 1.0 / (2.0 * s * s);
    let xr = centres_within(0u, c.x - reach, c.x + reach);
    let zr = centres_within(2u, c.z - reach, c.z + reach);
    let axis = p.density * s * sqrt(2.0 * 3.14159265);
    let scatter = p.albedo * bitcast<f32>(frame.forward_bits);
    let n = frame.resolution;
    var y: vec2<u32>;
    var end: u32;
    let k = 1.0 / (s * 1.41421356);
    if frame.pieces != 0u {
        y = centres_within(1u, c.y - radius, c.y + radius);
        end = min(y.y + 1u, n);
        for (var j = y.x + local; j < min(end, y.x + CACHED); j += 64u) {
            shares[j - y.x] = share(j, y, c.y, k);
        }
    } else {
        y = vec2<u32>(centres_within(1u, c.y - radius, 1e30).x, 0u);
        end = y.x + 1u;
    }
    workgroupBarrier();
    if y.x >= end || y.x >= n {
        return;
    }
    let nx = xr.y - xr.x;
    let nz = zr.y - zr.x;
    for (var col = local; col < nx * nz; col += 64u) {
        let ix = xr.x + col / nz;
        let iz = zr.x + col % nz;
        let dx = centre(0u, ix) - c.x;
        let dz = centre(2u, iz) - c.z;
        if frame.pieces != 0u {
            let w = -(1.0 - scatter) * axis * exp(-dx * dx * inv_2s2) * exp(-dz * dz * inv_2s2);
            for (var j = y.x; j < end; j++) {
                var sh: f32;
                if j - y.x < CACHED {
                    sh = shares[j - y.x];
                } else {
                    sh = share(j, y, c.y, k);
                }
                add(ix, j, iz, w * sh);
            }
        } else {
            let tau = axis * exp(-dx * dx * inv_2s2) * exp(-dz * dz * inv_2s2);
            add(ix, y.x, iz, log(exp(-tau) + scatter * tau));
        }
    }
}
