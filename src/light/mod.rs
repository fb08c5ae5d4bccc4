//! Light transport in closed form, beside the Monte Carlo estimators: what the oracle's tests and, later, an
//! exact unoccluded emitter term on the GPU compute without sampling.
//!
//! - [`polygon`]: the irradiance from a uniform Lambertian polygon (Lambert's formula), clipped to a sensor's
//!   domain;
//! - [`groups`]: the scene's emitters gathered into light groups, whose visibility sensors measure apart.

pub mod groups;
pub mod polygon;
