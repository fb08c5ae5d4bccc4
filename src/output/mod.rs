//! What the program writes: EXR (linear radiance and AOVs), PNG, plots, always atomically; results on
//! standard output.

pub mod atomic;
pub mod compare;
pub mod exr;
pub mod plot;
pub mod png;
pub mod stdout;
