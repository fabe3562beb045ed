//! References for the cloud light pass: the exact transmittance of a particle field,
//! and the paper's own way of filling the intensity buffer (clouds 4.1), slice by slice
//! with shadow polygons, which the prefix-sum fill of [`crate::clouds::buffer`] must
//! equal.

use glam::Vec3;

use crate::clouds::buffer::{IntensityBuffer, FOOTPRINT};
use crate::clouds::particles::Particle;

/// The fraction of sunlight arriving at `point` through `particles` with nothing
/// scattered into its path: `exp(-tau)`, `tau` the optical depth from the sun (along
/// `-to_sun`) to the point, summed exactly particle by particle.
pub fn transmittance(particles: &[Particle], to_sun: Vec3, point: Vec3) -> f64 {
    let light = -to_sun.normalize();
    let tau: f64 = particles
        .iter()
        .map(|p| {
            let d = point - p.position;
            let along = d.dot(light);
            let b = (d - along * light).length();
            p.column(b as f64, f64::NEG_INFINITY, along as f64)
        })
        .sum();
    (-tau).exp()
}

/// `Gamma` at the centres of `grid`'s voxels as the paper computes it: for each
/// particle, each slice perpendicular to `z` within its footprint gets a rectangle
/// covering the footprint's width and everything from its sun-side edge on, filled with its
/// factor `G = a tau p(l,l)/4pi + T` at each voxel's distance from the particle's axis,
/// and the rectangles are multiplied in. `[x][z][y]` like [`IntensityBuffer::log_gamma`].
pub fn shadow_polygons(grid: &IntensityBuffer, particles: &[Particle], forward: f32) -> Vec<f32> {
    let n = grid.resolution;
    let mut gamma = vec![1.0f64; n * n * n];
    let centre = |axis: usize, i: usize| grid.min[axis] + (i as f32 + 0.5) * grid.voxel[axis];
    for p in particles {
        let c = grid.buffer_from_world * p.position;
        let reach = FOOTPRINT * p.sigma();
        for iz in 0..n {
            let dz = centre(2, iz) - c.z;
            if dz.abs() > reach {
                continue;
            }
            for ix in 0..n {
                let dx = centre(0, ix) - c.x;
                if dx.abs() > reach {
                    continue;
                }
                let b = ((dx * dx + dz * dz) as f64).sqrt();
                let tau = p.column(b, f64::NEG_INFINITY, f64::INFINITY);
                let g = (-tau).exp() + p.albedo as f64 * forward as f64 * tau;
                for iy in 0..n {
                    if centre(1, iy) >= c.y - p.radius {
                        gamma[(ix * n + iz) * n + iy] *= g;
                    }
                }
            }
        }
    }
    gamma.into_iter().map(|g| g as f32).collect()
}
