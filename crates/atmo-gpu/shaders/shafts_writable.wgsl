// The shafts' working buffers as the compute passes see them: written.

// Light-space depth of the nearest surface per shadow-map texel, [light][row][column].
@group(0) @binding(5) var<storage, read_write> depth: array<f32>;
// Per light, 10 order-preserving u32 encodings: camera depth min and max of the ray
// ends, their largest squared distance to the lamp and to the eye, their box min, max.
@group(0) @binding(6) var<storage, read_write> extents: array<atomic<u32>>;
// Per light 12 floats (eye in light space, lamp in haze, box min, z_near, box max,
// z_far), then the attenuation table's scales (s_scale, t_scale, ds, dt).
@group(0) @binding(7) var<storage, read_write> derived: array<f32>;
// Where each sub-pixel ray ends (m from the eye), [sub-pixel][pixel].
@group(0) @binding(8) var<storage, read_write> ends: array<f32>;
// The picture, linear RGB.
@group(0) @binding(9) var<storage, read_write> out: array<vec4<f32>>;
