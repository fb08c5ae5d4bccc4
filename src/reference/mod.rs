//! The CPU reference: an independent implementation of the same estimator by ray casting, the oracle every
//! GPU image is tested against (docs/DESIGN.md §6).

pub mod gbuffer;
pub mod integrator;
pub mod lights;
pub mod post;
pub mod sampling;
