//! What the program writes: EXR (linear radiance and AOVs), always atomically.

pub mod atomic;
pub mod compare;
pub mod exr;
pub mod plot;
pub mod png;
