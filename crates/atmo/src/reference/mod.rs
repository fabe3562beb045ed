//! Slow, obviously-correct integrators that the fast methods are tested against.
//!
//! They share only the physics with the fast methods (densities, coefficients, phase
//! functions, the sun's visible fraction; the scene and its geometry): no tables, no
//! shells, no maps, no shadow maps. The sky's integrals are composite Gauss-Legendre
//! with a resolution that the tests show converged; the shafts' are midpoint ray
//! marching with shadow rays, converged by doubling.

pub mod clouds;
pub mod sampling;
pub mod shafts;
pub mod sky;
