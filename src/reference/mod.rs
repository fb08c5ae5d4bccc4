//! The CPU reference: an independent implementation of the same estimator by ray casting, the oracle every
//! GPU image is tested against (docs/DESIGN.md §6): `integrator` at the visible point (direct light, the
//! paper's ε), `path` the path a direction starts there with global illumination, `lights` the emitters as
//! a distribution, `sampling` the random numbers, `post` the CPU twins of the post-passes. The visible points
//! come from the host G-buffer's ray caster (`gbuffer::cast`).

pub mod integrator;
pub mod lights;
pub mod path;
pub mod post;
pub mod sampling;
