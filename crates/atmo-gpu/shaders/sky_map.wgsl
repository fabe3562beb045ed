// The skylight map from the SVD table, sky 4.2 and (17): per view direction and
// channel, sum_k t_k(sun, h) s_k(theta, phi) over the T(theta, phi) terms that row
// keeps. One invocation per row, rows in the table's order (decreasing term count), so
// neighbouring invocations read neighbouring s_k and stop at nearly the same k.

// Mirrors atmo_gpu::sky::SkyMapParams.
struct SkyMapParams {
    rows: u32,
    terms: u32,
    directions: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: SkyMapParams;
// s_k term after term: term k of the row at position i is s[offset_k + i].
@group(0) @binding(1) var<storage, read> s: array<f32>;
// The row (channel * directions + direction) at each position.
@group(0) @binding(2) var<storage, read> order: array<u32>;
// used[k]: how many rows use term k (decreasing in k).
@group(0) @binding(3) var<storage, read> used: array<u32>;
// t_k interpolated at this sun and altitude (atmo's SkylightTable::coefficients).
@group(0) @binding(4) var<storage, read> coefficients: array<f32>;
// Out: linear sRGB radiance, [direction][channel].
@group(0) @binding(5) var<storage, read_write> map: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.rows {
        return;
    }
    var acc = 0.0;
    var offset = 0u;
    for (var k = 0u; k < params.terms; k++) {
        let n = used[k];
        if i >= n {
            break;
        }
        acc += coefficients[k] * s[offset + i];
        offset += n;
    }
    let row = order[i];
    // The table stores sqrt(radiance); negative sums (truncation ringing) are zero.
    let y = max(acc, 0.0);
    map[(row % params.directions) * 3u + row / params.directions] = y * y;
}
