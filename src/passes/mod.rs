//! GPU passes, one file each, in pipeline order (DESIGN.md §3). Each pass owns its pipeline, layouts and
//! descriptors and is named after the shaders it runs (`glsl/<pass>.*`).

pub mod compose;
pub mod fill;
pub mod filter;
pub mod gbuffer;
pub mod interpolate;
pub mod reduce;
pub mod sensor_maps;
