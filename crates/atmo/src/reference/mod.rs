//! Slow, obviously-correct integrators that the fast methods are tested against.
//!
//! They share only the physics with the fast methods (densities, coefficients, phase
//! functions, the sun's visible fraction): no tables, no shells, no maps. Every
//! integral is composite Gauss-Legendre with a resolution that the tests show converged.

pub mod sky;
