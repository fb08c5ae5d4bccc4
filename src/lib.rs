//! sensorlight: global illumination by Sensor-Based Lighting (Banquiero & Leone) on Vulkan.
//!
//! Module map, in pipeline order (docs/DESIGN.md §3):
//! - [`scene`]: TOML scene files, OBJ/MTL meshes, surface ids, the camera;
//! - [`vk`]: the Vulkan layer (device, buffers, images, pipelines), one owner per object;
//! - [`gpu_types`] (+ `glsl/types.glsl`): the structs shared with shaders; [`gpu_scene`]: the scene on the GPU;
//! - [`passes`]: the GPU passes, one per file, each beside its shaders in `glsl/`;
//! - [`sensors`]: sensor frames, layer layouts and texel weights (shared by GPU and CPU);
//! - [`renderer`]: one render end to end, the passes in order; [`strategy`]: which sensor-map batching
//!   strategy, self-checked and measured per device;
//! - [`reference`](mod@reference): the CPU ray-casting reference of the same estimator; [`light`]: closed forms it is
//!   tested against (exact polygon irradiance);
//! - [`gi`]: global illumination, the radiance cache the sensors fill and see, bounce by bounce;
//! - [`params`]: the algorithm's parameters, defaults and checks;
//! - [`output`]: EXR and PNG writing, always atomic; [`errors`]: how an error is told to the user;
//!   [`cancel`]: stopping a render part-way (SIGINT, SIGTERM), cleanly;
//! - [`viewer`]: a window that shows a render converging and restarts it as the camera moves.

pub mod bake;
pub mod bench;
pub mod cancel;
pub mod clusters;
pub mod errors;
pub mod gbuffer;
pub mod gi;
pub mod gpu_scene;
pub mod gpu_types;
pub mod light;
pub mod lightmap;
pub mod metrics;
pub mod output;
pub mod params;
pub mod passes;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod sensors;
pub mod strategy;
pub mod supersample;
pub mod viewer;
pub mod vk;

/// SPIR-V of every shader in `glsl/`, compiled by build.rs: `glsl/gbuffer.vert` is `shaders::GBUFFER_VERT`.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
