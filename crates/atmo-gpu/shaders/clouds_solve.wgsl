// The transfer solve of the clouds' orders past the first (atmo::clouds::diffusion,
// pass for pass; its module doc and docs/clouds.md, "Every order: the transfer
// solve"): the sun's transmittance at each cell, the light scattered once swept along
// DIRECTIONS directions, the diffusion's sources, the flux-limited faces, the
// conjugate gradients, the fluence and flux per cell, and the light each cell sends
// toward the eye; and the sky's light through the same solve (its transmittance from the
// grid's faces swept along the same directions, its diffusion per channel). Follows
// clouds_common.wgsl and clouds_lookup.wgsl. Every array is per cell, [x][y][z] (z
// fastest), as the CPU's; `sources`, `phi` and `fields` hold four segments of `stride`
// cells each, the sun's field's and the sky's per channel, and the passes of one field
// are bound to its segment.

// Mirrors atmo_gpu::clouds::SolveParams.
struct SolveParams {
    // World position of cell (0, 0, 0)'s centre (m); w: the cells' side h (m).
    first_centre: vec4<f32>,
    // The eye the light toward the eye is made for (m).
    eye: vec4<f32>,
    // Cells along x, y and z; w: all of them.
    dims: vec4<u32>,
    // The phase's mean cosine g and delta-Eddington's share f; the most D may be (m).
    g: f32,
    f: f32,
    d_max: f32,
    // The most conjugate-gradient iterations of one solve.
    limit: u32,
    // Cells a segment of `sources`, `phi` and `fields`; 1 where the sky's light is
    // solved.
    stride: u32,
    sky: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> solve: SolveParams;
// sigma_t and sigma_s (1/m, the particles' mean over the cell), the sun's transmittance
// at the centre, unused.
@group(0) @binding(1) var<storage, read_write> medium: array<vec4<f32>>;
// The closure (CLOSURE_AT), the phase over the cosine (LOBE_AT), each direction's share
// of the sunlight scattered once (SHARES_AT), the directions (DIRECTIONS_AT, xyz) and
// the sky's radiance arriving along each (RADIANCE_AT, RGB).
@group(0) @binding(2) var<storage, read> tables: array<f32>;
// [direction][cell]: the light scattered once per unit sun irradiance (1/sr); then,
// from DIRECTIONS n on, the transmittance from the grid's faces along each direction.
@group(0) @binding(3) var<storage, read_write> once: array<f32>;
// The diffusion's sources: Q1 (xyz) and Q0 (w).
@group(0) @binding(4) var<storage, read_write> sources: array<vec4<f32>>;
// D on the faces to the + side along x, y, z (0 where either side is clear air), and
// the system's diagonal (w).
@group(0) @binding(5) var<storage, read_write> faces: array<vec4<f32>>;
// The fluence phi, kept between solves to start the next from.
@group(0) @binding(6) var<storage, read_write> phi: array<f32>;
// The conjugate gradients' right side b, residual r, direction p and A p (xyzw); after
// them the cells' phi / 4 pi and F / 4 pi before the air beside the cloud is filled.
@group(0) @binding(7) var<storage, read_write> work: array<vec4<f32>>;
// Per cell phi / 4 pi and F / 4 pi, per unit sun irradiance.
@group(0) @binding(8) var<storage, read_write> fields: array<vec4<f32>>;
// The light each cell sends toward the eye per unit scattering coefficient: the sun's
// (1/sr per unit sun irradiance) and the sky's (RGB, its radiance's units).
@group(0) @binding(9) var<storage, read_write> seen: array<vec4<f32>>;
// The sun's light pass: its frame and its grid (clouds_lookup.wgsl reads them).
@group(0) @binding(10) var<uniform> frame: BufferFrame;
@group(0) @binding(11) var<storage, read> log_gamma: array<f32>;
// The conjugate-gradient iterations taken, summed over the solve's lags.
@group(0) @binding(12) var<storage, read_write> counts: array<u32>;

const CLOSURE_AT: u32 = 0u;
const LOBE_AT: u32 = (CLOSURE_STEPS + 1u) * (CLOSURE_STEPS + 1u);
const SHARES_AT: u32 = LOBE_AT + LOBE_STEPS + 1u;
const DIRECTIONS_AT: u32 = SHARES_AT + DIRECTIONS;
const RADIANCE_AT: u32 = DIRECTIONS_AT + 3u * DIRECTIONS;

// The single workgroup's size of the passes that loop over the whole grid.
const SOLVE_GROUP: u32 = 256u;

fn cell_count() -> u32 {
    return solve.dims.w;
}

fn side() -> f32 {
    return solve.first_centre.w;
}

fn strides() -> vec3<u32> {
    return vec3<u32>(solve.dims.y * solve.dims.z, solve.dims.z, 1u);
}

fn index_of(cell: u32) -> vec3<u32> {
    let d = solve.dims;
    return vec3<u32>(cell / (d.y * d.z), cell / d.z % d.y, cell % d.z);
}

// The cell to the + side of `cell` along `axis`, or n (none).
fn next_of(cell: u32, axis: u32) -> u32 {
    if index_of(cell)[axis] + 1u < solve.dims[axis] {
        return cell + strides()[axis];
    }
    return cell_count();
}

// The cell to the - side, or n.
fn previous_of(cell: u32, axis: u32) -> u32 {
    if index_of(cell)[axis] > 0u {
        return cell - strides()[axis];
    }
    return cell_count();
}

// Medium::inside: the cell's optical depth across at least THIN.
fn inside(cell: u32) -> bool {
    return cell < cell_count() && medium[cell].x * side() >= THIN;
}

fn joined(cell: u32, other: u32) -> bool {
    return other < cell_count() && inside(cell) && inside(other);
}

fn sigma_tr(cell: u32) -> f32 {
    let m = medium[cell];
    return max(m.x - solve.g * m.y, 0.0);
}

// 1 / (3 sigma_tr), capped at d_max (no limit for clear air).
fn plain_d(tr: f32) -> f32 {
    if tr > 0.0 {
        return min(1.0 / (3.0 * tr), solve.d_max);
    }
    return solve.d_max;
}

// Medium::marshak: the flux out through an outer face per unit fluence.
fn marshak(cell: u32) -> f32 {
    return 1.0 / (0.5 * side() / plain_d(sigma_tr(cell)) + 2.0);
}

fn direction(d: u32) -> vec3<f32> {
    let at = DIRECTIONS_AT + 3u * d;
    return vec3<f32>(tables[at], tables[at + 1u], tables[at + 2u]);
}

// The sky's radiance arriving along direction d (from the opposite way), RGB.
fn sky_radiance(d: u32) -> vec3<f32> {
    let at = RADIANCE_AT + 3u * d;
    return vec3<f32>(tables[at], tables[at + 1u], tables[at + 2u]);
}

// The transmittance from the grid's faces along direction d at `cell`.
fn through(d: u32, cell: u32) -> f32 {
    return once[(DIRECTIONS + d) * cell_count() + cell];
}

// Lobe::at: the phase at the cosine, linear between the table's steps.
fn lobe(cosine: f32) -> f32 {
    let x = (clamp(cosine, -1.0, 1.0) + 1.0) * 0.5 * f32(LOBE_STEPS);
    let i = min(u32(x), LOBE_STEPS - 1u);
    let a = tables[LOBE_AT + i];
    return a + (x - f32(i)) * (tables[LOBE_AT + i + 1u] - a);
}

// Closure::at: the closure at r = |F| / phi and the cosine, bilinear.
fn closure(r: f32, cosine: f32) -> f32 {
    let n = f32(CLOSURE_STEPS);
    let x = clamp(r / CLOSURE_MAX, 0.0, 1.0) * n;
    let y = (clamp(cosine, -1.0, 1.0) + 1.0) * 0.5 * n;
    let i = min(u32(x), CLOSURE_STEPS - 1u);
    let j = min(u32(y), CLOSURE_STEPS - 1u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let row = CLOSURE_STEPS + 1u;
    let at = CLOSURE_AT + i * row + j;
    let low = tables[at] + fy * (tables[at + 1u] - tables[at]);
    let high = tables[at + row] + fy * (tables[at + row + 1u] - tables[at + row]);
    return low + fx * (high - low);
}

// A wide pass's invocation: one a cell, the dispatch spread over (x, y) workgroups of
// 64 (flat_index).
struct Wide {
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
}

fn cell_of(at: Wide) -> u32 {
    return flat_index(at.group, at.groups, at.local);
}

// The sun's transmittance at each cell's centre (IntensityBuffer::sample).
@compute @workgroup_size(64)
fn sunlight(at: Wide) {
    let cell = cell_of(at);
    if cell >= cell_count() {
        return;
    }
    let centre = solve.first_centre.xyz + vec3<f32>(index_of(cell)) * side();
    medium[cell].z = exp(log_gamma_in(frame, 0u, grid_of(frame, centre)));
}

// The light scattered once along each direction (diffusion::sweep): a workgroup a
// direction, sweeping the grid in wavefronts from its upwind corner (each cell's upwind
// neighbours are on the wavefront before), each cell's light its upwind neighbours'
// attenuated across it and its own source added, exact for a homogeneous cell. The
// workgroups past the first DIRECTIONS sweep radiance 1 from outside the grid, with no
// source: the transmittance the sky's light is carried by.
@compute @workgroup_size(256)
fn sweep(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let from_outside = group.x >= DIRECTIONS;
    let d = group.x % DIRECTIONS;
    let w = direction(d);
    let share = select(tables[SHARES_AT + d], 0.0, from_outside);
    let outside = select(0.0, 1.0, from_outside);
    let n = solve.dims.xyz;
    let s = strides();
    let base = group.x * cell_count();
    let rate = abs(w) / side();
    let across = rate.x + rate.y + rate.z;
    let ahead = w >= vec3<f32>(0.0);
    let wavefronts = n.x + n.y + n.z - 2u;
    for (var front = 0u; front <= wavefronts; front++) {
        for (var k = local; k < n.x * n.y; k += SOLVE_GROUP) {
            // The cell at (a, b, c) from the upwind corner, a + b + c = front.
            let a = k / n.y;
            let b = k % n.y;
            if front < a + b || front - a - b >= n.z {
                continue;
            }
            let upwind = vec3<u32>(a, b, front - a - b);
            let index = select(n - vec3<u32>(1u) - upwind, upwind, ahead);
            let cell = dot(index, s);
            var inflow = 0.0;
            for (var axis = 0u; axis < 3u; axis++) {
                var upstream = outside;
                if upwind[axis] > 0u {
                    let neighbour = select(cell + s[axis], cell - s[axis], ahead[axis]);
                    upstream = once[base + neighbour];
                    if from_outside {
                        let m = medium[neighbour];
                        upstream *= exit_over_mean((m.x - solve.f * m.y) / across);
                    }
                }
                inflow += rate[axis] * upstream;
            }
            let m = medium[cell];
            let emitted = m.y * m.z * share;
            let extinction = m.x - solve.f * m.y;
            let tau = extinction / across;
            let kept = exp(-tau);
            var own = emitted / across;
            if tau > 1e-4 {
                own = emitted / extinction * (1.0 - kept);
            }
            // From outside, the cell's mean along its path (diffusion::Sweep).
            once[base + cell] = select(
                inflow / across * kept + own,
                inflow / across * kept / exit_over_mean(tau),
                from_outside,
            );
        }
        storageBarrier();
    }
}

// A cell's exit over its mean along the path across it (diffusion::exit_over_mean).
fn exit_over_mean(tau: f32) -> f32 {
    if tau > 1e-4 {
        return tau / (exp(tau) - 1.0);
    }
    return 1.0 - 0.5 * tau;
}

// The diffusion's sources from the light scattered once (Medium::scatter): its second
// scattering less the share f that goes on ahead with it.
@compute @workgroup_size(64)
fn scatter(at: Wide) {
    let cell = cell_of(at);
    let n = cell_count();
    if cell >= n {
        return;
    }
    var m = vec4<f32>(0.0);
    for (var d = 0u; d < DIRECTIONS; d++) {
        m += vec4<f32>(1.0, direction(d)) * once[d * n + cell];
    }
    m *= 4.0 * PI / f32(DIRECTIONS);
    sources[cell] = diffusion_source(cell, m);
}

// The diffusion's source from a field's fluence and flux m (xyzw) at `cell`.
fn diffusion_source(cell: u32, m: vec4<f32>) -> vec4<f32> {
    let f = solve.f;
    let second = (1.0 - f) * medium[cell].y;
    let g_scaled = (solve.g - f) / (1.0 - f);
    return vec4<f32>(g_scaled * second * m.yzw, second * m.x);
}

// The sky's diffusion sources per channel (diffusion::SkyField): the scattering of its
// light carried in from the grid's faces, into the sources' segments 1 to 3.
@compute @workgroup_size(64)
fn scatter_sky(at: Wide) {
    let cell = cell_of(at);
    let n = cell_count();
    if cell >= n {
        return;
    }
    var m = array<vec4<f32>, 3>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    for (var d = 0u; d < DIRECTIONS; d++) {
        let basis = vec4<f32>(1.0, direction(d)) * through(d, cell);
        let l = sky_radiance(d);
        for (var c = 0u; c < 3u; c++) {
            m[c] += basis * l[c];
        }
    }
    for (var c = 0u; c < 3u; c++) {
        sources[(1u + c) * solve.stride + cell] =
            diffusion_source(cell, m[c] * (4.0 * PI / f32(DIRECTIONS)));
    }
}

// The fluence's gradient at `cell` by central differences (0 beyond the grid).
fn gradient(cell: u32) -> vec3<f32> {
    var g = vec3<f32>(0.0);
    for (var axis = 0u; axis < 3u; axis++) {
        let up = next_of(cell, axis);
        let down = previous_of(cell, axis);
        var v = 0.0;
        if up < cell_count() {
            v += phi[up];
        }
        if down < cell_count() {
            v -= phi[down];
        }
        g[axis] = v / (2.0 * side());
    }
    return g;
}

// diffusion::limited_d: Levermore and Pomraning's D with the streaming limit.
fn limited_d(grad: f32, phi_f: f32, tr: f32) -> f32 {
    let k = STREAMING;
    if !(phi_f > 0.0 && grad > 0.0) {
        return plain_d(tr);
    }
    if tr <= 0.0 {
        return k * phi_f / grad;
    }
    let r = grad / (k * tr * phi_f);
    if r < 1e-3 {
        return plain_d(tr);
    }
    var coth = 1.0;
    if r <= 20.0 {
        coth = 1.0 / tanh(r);
    }
    return (coth - 1.0 / r) * k * phi_f / grad;
}

// D on the face between `cell` and the next along `axis` (both cloud): by the faces'
// mean sigma_tr, or by the limiter from the fluence.
fn face_d(cell: u32, next: u32, axis: u32, limited: bool) -> f32 {
    let tr = 0.5 * (sigma_tr(cell) + sigma_tr(next));
    if !limited {
        return plain_d(tr);
    }
    var grad = 0.5 * (gradient(cell) + gradient(next));
    grad[axis] = (phi[next] - phi[cell]) / side();
    let phi_f = 0.5 * (phi[cell] + phi[next]);
    return min(limited_d(length(grad), phi_f, tr), solve.d_max);
}

// Faces::with: D on the + faces and the system's diagonal (1 for clear air, which the
// solve leaves out; the outer faces' Marshak outflow for the cloud's).
fn make_faces(cell: u32, limited: bool) {
    var d = vec3<f32>(0.0);
    var diagonal = 1.0;
    if inside(cell) {
        let h2 = side() * side();
        var outer = 0.0;
        var sum = 0.0;
        for (var axis = 0u; axis < 3u; axis++) {
            let next = next_of(cell, axis);
            if joined(cell, next) {
                d[axis] = face_d(cell, next, axis, limited);
            } else {
                outer += 1.0;
            }
            let previous = previous_of(cell, axis);
            if joined(cell, previous) {
                sum += face_d(previous, cell, axis, limited) / h2;
            } else {
                outer += 1.0;
            }
        }
        let m = medium[cell];
        diagonal = outer * marshak(cell) / side() + max(m.x - m.y, 0.0) + sum
            + (d.x + d.y + d.z) / h2;
    }
    faces[cell] = vec4<f32>(d, diagonal);
}

// The faces of the first lag from scratch.
@compute @workgroup_size(64)
fn faces_plain(at: Wide) {
    let cell = cell_of(at);
    if cell < cell_count() {
        make_faces(cell, false);
    }
}

// The faces by the flux limiter from the fluence.
@compute @workgroup_size(64)
fn faces_limited(at: Wide) {
    let cell = cell_of(at);
    if cell < cell_count() {
        make_faces(cell, true);
    }
}

// Faces::drift: 3 D Q1 . n across the face to the + side of `cell`.
fn drift(cell: u32, next: u32, axis: u32) -> f32 {
    return 3.0 * faces[cell][axis] * 0.5 * (sources[cell][axis] + sources[next][axis]);
}

// Faces::right_side: Q0 less the divergence of the drift, into work.x.
@compute @workgroup_size(64)
fn right_side(at: Wide) {
    let cell = cell_of(at);
    let n = cell_count();
    if cell >= n {
        return;
    }
    var b = 0.0;
    if inside(cell) {
        b = sources[cell].w;
        for (var axis = 0u; axis < 3u; axis++) {
            let next = next_of(cell, axis);
            if next < n {
                b -= drift(cell, next, axis) / side();
            }
            let previous = previous_of(cell, axis);
            if previous < n {
                b += drift(previous, cell, axis) / side();
            }
        }
    }
    work[cell] = vec4<f32>(b, 0.0, 0.0, 0.0);
}

// (A x)[cell], x the fluence (`of_phi`) or the direction p (Faces::apply).
fn apply(cell: u32, of_phi: bool) -> f32 {
    let n = cell_count();
    var off = 0.0;
    for (var axis = 0u; axis < 3u; axis++) {
        let next = next_of(cell, axis);
        if next < n {
            off += faces[cell][axis] * select(work[next].z, phi[next], of_phi);
        }
        let previous = previous_of(cell, axis);
        if previous < n {
            off += faces[previous][axis] * select(work[previous].z, phi[previous], of_phi);
        }
    }
    let x = select(work[cell].z, phi[cell], of_phi);
    return faces[cell].w * x - off / (side() * side());
}

var<workgroup> partial: array<vec3<f32>, SOLVE_GROUP>;

// The workgroup's sum of each invocation's `v`, the same in all of them; the grid's
// writes before it are seen by all after it.
fn total(local: u32, v: vec3<f32>) -> vec3<f32> {
    partial[local] = v;
    storageBarrier();
    workgroupBarrier();
    for (var stride = SOLVE_GROUP / 2u; stride > 0u; stride /= 2u) {
        if local < stride {
            partial[local] += partial[local + stride];
        }
        workgroupBarrier();
    }
    return workgroupUniformLoad(&partial[0]);
}

// Conjugate gradients preconditioned by the diagonal, from the fluence held, to
// TOLERANCE of the right side (diffusion::conjugate_gradients): one workgroup over the
// whole grid, so that its sums need no other pass.
@compute @workgroup_size(256)
fn conjugate_gradients(@builtin(local_invocation_index) local: u32) {
    let n = cell_count();
    var sums = vec3<f32>(0.0);
    for (var cell = local; cell < n; cell += SOLVE_GROUP) {
        var w = work[cell];
        let r = w.x - apply(cell, true);
        let z = r / faces[cell].w;
        w.y = r;
        w.z = z;
        work[cell] = w;
        sums += vec3<f32>(r * z, w.x * w.x, r * r);
    }
    var t = total(local, sums);
    var rz = t.x;
    let goal = f32(TOLERANCE) * sqrt(t.y);
    var rr = t.z;
    var iterations = 0u;
    loop {
        if sqrt(rr) <= goal || iterations >= solve.limit {
            break;
        }
        var pq = 0.0;
        for (var cell = local; cell < n; cell += SOLVE_GROUP) {
            let q = apply(cell, false);
            work[cell].w = q;
            pq += work[cell].z * q;
        }
        let alpha = rz / total(local, vec3<f32>(pq, 0.0, 0.0)).x;
        var next = vec3<f32>(0.0);
        for (var cell = local; cell < n; cell += SOLVE_GROUP) {
            var w = work[cell];
            phi[cell] += alpha * w.z;
            w.y -= alpha * w.w;
            work[cell] = w;
            next += vec3<f32>(w.y * w.y / faces[cell].w, w.y * w.y, 0.0);
        }
        t = total(local, next);
        let beta = t.x / rz;
        rz = t.x;
        rr = t.y;
        for (var cell = local; cell < n; cell += SOLVE_GROUP) {
            var w = work[cell];
            w.z = w.y / faces[cell].w + beta * w.z;
            work[cell] = w;
        }
        storageBarrier();
        iterations++;
    }
    if local == 0u {
        counts[0] += iterations;
    }
}

// Faces::values: per cell phi / 4 pi and F / 4 pi, F the mean of the flux through its
// two faces along each axis (the outer faces' by Marshak's condition), into work.
@compute @workgroup_size(64)
fn moments(at: Wide) {
    let cell = cell_of(at);
    if cell >= cell_count() {
        return;
    }
    if !inside(cell) {
        work[cell] = vec4<f32>(0.0);
        return;
    }
    let h = side();
    let out = phi[cell] * marshak(cell);
    var flux = vec3<f32>(0.0);
    for (var axis = 0u; axis < 3u; axis++) {
        var up = out;
        let next = next_of(cell, axis);
        if joined(cell, next) {
            up = -faces[cell][axis] * (phi[next] - phi[cell]) / h + drift(cell, next, axis);
        }
        var down = -out;
        let previous = previous_of(cell, axis);
        if joined(cell, previous) {
            down = -faces[previous][axis] * (phi[cell] - phi[previous]) / h
                + drift(previous, cell, axis);
        }
        flux[axis] = 0.5 * (up + down);
    }
    work[cell] = vec4<f32>(max(phi[cell], 0.0), flux) / (4.0 * PI);
}

// Medium::dilated: each cell of clear air beside the cloud the mean of its cloud
// neighbours' values, so that lookups across the fringe do not fade toward 0.
@compute @workgroup_size(64)
fn dilate(at: Wide) {
    let cell = cell_of(at);
    if cell >= cell_count() {
        return;
    }
    if inside(cell) {
        fields[cell] = work[cell];
        return;
    }
    var sum = vec4<f32>(0.0);
    var count = 0.0;
    for (var axis = 0u; axis < 3u; axis++) {
        for (var end = 0u; end < 2u; end++) {
            let other = select(previous_of(cell, axis), next_of(cell, axis), end == 0u);
            if inside(other) {
                sum += work[other];
                count += 1.0;
            }
        }
    }
    fields[cell] = select(vec4<f32>(0.0), sum / max(count, 1.0), count > 0.0);
}

// DiffuseLight::toward: the light each cell's centre sends toward the eye, the second
// order's by the whole phase and the diffuse field's by the closure.
@compute @workgroup_size(64)
fn toward(at: Wide) {
    let cell = cell_of(at);
    let n = cell_count();
    if cell >= n {
        return;
    }
    let centre = solve.first_centre.xyz + vec3<f32>(index_of(cell)) * side();
    let to_eye = solve.eye.xyz - centre;
    var w = vec3<f32>(0.0);
    if dot(to_eye, to_eye) > 0.0 {
        w = normalize(to_eye);
    }
    // DiffuseLight::both_toward: the lights carried along the directions scattered by
    // the phase (normalised over them), read once for the sun's and the sky's, then the
    // diffuse fields' by the closure.
    let with_sky = solve.sky != 0u;
    var second = 0.0;
    var sky = vec3<f32>(0.0);
    var norm = 0.0;
    for (var d = 0u; d < DIRECTIONS; d++) {
        let p = lobe(dot(direction(d), w));
        second += p * once[d * n + cell];
        if with_sky {
            sky += p * through(d, cell) * sky_radiance(d);
        }
        norm += p;
    }
    if norm > 0.0 {
        second /= norm;
        sky /= norm;
    }
    if with_sky {
        for (var c = 0u; c < 3u; c++) {
            sky[c] += leaving(fields[(1u + c) * solve.stride + cell], w);
        }
    }
    seen[cell] = vec4<f32>(leaving(fields[cell], w) + second, sky);
}

// DiffuseLight::leaving: what a droplet scatters along w of the diffuse field of
// fluence and flux v.
fn leaving(v: vec4<f32>, w: vec3<f32>) -> f32 {
    if !(v.x > 0.0) {
        return 0.0;
    }
    let size = length(v.yzw);
    var cosine = 0.0;
    if size > 0.0 {
        cosine = dot(v.yzw, w) / size;
    }
    return v.x * closure(size / v.x, cosine);
}
