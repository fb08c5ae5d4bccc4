//! GPU passes, one file each, in pipeline order (DESIGN.md §3). Each pass owns its pipeline, layouts and
//! descriptors and is named after the shaders it runs (`glsl/<pass>.*`).

pub mod gbuffer;
