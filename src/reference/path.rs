//! Global illumination in the oracle: the path a sensor's direction starts (docs/DESIGN.md §6).
//!
//! With `Indirect::Bounces` the light a direction from the visible point `p` brings back is the radiance
//! leaving the surface `x₁` it hits, `Le(x₁) + Kd(x₁)·R(x₁)`, and `R(x₁)` is the same integral one vertex
//! further on: a path. At every vertex `x_k` (k ≥ 1):
//!
//! - the normal (the shading normal, `Mesh::shading_normal`) is turned towards the side the ray arrived on
//!   (every surface reflects on both sides), and the
//!   vertex's rays leave from it lifted by the sensor's bias and are blind to the near distance, as at `p`
//!   (`sensors::frame`), so a vertex in a corner sees the room and not the seam;
//! - next-event estimation: a point on an emitter (by power), MIS-weighted (power heuristic) against
//! - a cosine direction over the whole hemisphere, which continues the path: the front of an emitter it hits
//!   adds that emitter's `Ke`, MIS-weighted against `x_k`'s light point; where it leaves the scene, the
//!   sky: the constant background (which no sample finds otherwise: weight 1), or the sky map's radiance,
//!   MIS-weighted against `x_k`'s direction drawn from the map (next-event estimation of the sky).
//!
//! The throughput `β` is the product of the `Kd` met beyond `p` (each cosine direction's density `cosθ/π`
//! cancels the Lambertian's `Kd·cosθ/π`), so a path's value is `Σ_k β_k·(direct light at x_k)`.
//!
//! **Length.** `Bounces::Fixed(N)`: at most `N` vertices beyond `p` reflect (`N = 0` is direct light, which
//! the integrator computes without this module; a path tracer's maximum depth `N + 2`).
//! `Bounces::Converged`: unbounded. From vertex [`ROULETTE_AFTER`] + 1 on (with `Fixed` too: it is
//! unbiased, and spares a deep count its long tail), Russian roulette: the path goes on with probability
//! `q = min(max β, MAX_SURVIVAL)` and `β /= q`. The cap (0.95, Mitsuba's) ends every path after at most 20
//! further vertices on average whatever the albedo, so albedo ≥ 1 terminates; where `Kd > 0.95` it lets `β`
//! grow by `Kd/0.95` per vertex, so a path whose throughput passes [`MAX_THROUGHPUT`] ends there. That is a
//! bias of the light beyond the vertex where it happens (≈ 440 vertices at Kd 0.98: `0.98⁴⁴⁰ ≈ 1e-4` of a
//! closed box's light); a closed scene of Kd ≥ 1 has no finite answer to be biased from. [`MAX_BOUNCES`]
//! bounds every path, so termination never rests on the random numbers (a path reaches it with probability
//! below `0.95¹⁰²⁰ ≈ 2e-23`).
//!
//! Random numbers: the first direction and light point are the integrator's Sobol points; vertex k's are
//! `HashedStream::vertex(sample, k)` of the replicate's key.

use std::f64::consts::PI;

use glam::Vec3;

use super::integrator::{Integrator, inside, power_heuristic};
use super::sampling::{VertexSamples, cosine_hemisphere};
use crate::params::Bounces;
use crate::scene::Ray;
use crate::sensors::frame::SensorFrame;

/// Vertices beyond `p` that always reflect; roulette decides from the next one on.
pub const ROULETTE_AFTER: u32 = 3;
/// The highest probability with which roulette lets a path go on.
pub const MAX_SURVIVAL: f32 = 0.95;
/// A path whose throughput (any channel) exceeds this ends: only albedos above [`MAX_SURVIVAL`] get there.
pub const MAX_THROUGHPUT: f32 = 1e6;
/// The most vertices beyond `p` any path reflects at, `Bounces::Converged` included.
pub const MAX_BOUNCES: u32 = 1024;

impl Integrator<'_> {
    /// One path from the sensor along the cosine direction `local` (sensor frame): what
    /// `direction_sample` counts at ε = 0 (the first hit's `Ke`, MIS-weighted; the background) plus the light
    /// the surfaces along the path reflect, through at most `bounces` of them. `vertex(k)` gives vertex k's
    /// random numbers.
    pub(super) fn path_sample(
        &self,
        sensor: &SensorFrame,
        local: Vec3,
        bounces: Bounces,
        vertex: impl Fn(u32) -> VertexSamples,
        rays: &mut u64,
    ) -> Vec3 {
        if self.frustum.is_some() && !inside(local, self.frustum) {
            return Vec3::ZERO; // outside the paper's square view: the sensor does not see it
        }
        let max_bounces = match bounces {
            Bounces::Fixed(n) => n.min(MAX_BOUNCES),
            Bounces::Converged => MAX_BOUNCES,
        };
        let mut ray = Ray::new(sensor.origin, sensor.to_world(local));
        // Density of the direction that cast `ray`: the MIS weight of the emitter it hits.
        let mut p_cosine = local.z as f64 / PI;
        let (mut beta, mut radiance) = (Vec3::ONE, Vec3::ZERO);
        let mut depth = 0;
        loop {
            *rays += 1;
            let Some(hit) = self.bvh.intersect(&ray, self.near, f32::INFINITY) else {
                let weight = power_heuristic(p_cosine, self.sky_pdf(ray.dir));
                return radiance + beta * self.sky(ray.dir) * weight as f32;
            };
            let tri = &self.scene.mesh.triangles[hit.triangle as usize];
            let material = self.scene.mesh.material_of(tri.surface);
            let cos_light = -ray.dir.dot(tri.normal);
            if cos_light > 0.0 && material.is_emitter() {
                let weight = self.lights.as_ref().map_or(1.0, |lights| {
                    let p_light = lights.area_pdf(hit.triangle) * (hit.t as f64).powi(2) / cos_light as f64;
                    power_heuristic(p_cosine, p_light)
                });
                radiance += beta * self.scene.mesh.emission_at(hit.triangle as usize, ray.at(hit.t)) * weight as f32;
            }
            if depth == max_bounces {
                return radiance;
            }
            depth += 1;
            let at = ray.at(hit.t);
            beta *= self.scene.mesh.albedo_at(hit.triangle as usize, at);
            let u = vertex(depth);
            if depth > ROULETTE_AFTER {
                let q = beta.max_element().min(MAX_SURVIVAL);
                if u.roulette >= q {
                    return radiance; // also where β = 0: q = 0
                }
                beta /= q;
            }
            if !(beta.max_element() > 0.0 && beta.max_element() <= MAX_THROUGHPUT) {
                return radiance; // black (nothing more to add) or past the cap (module docs)
            }
            let shading = self.scene.mesh.shading_normal(hit.triangle as usize, at);
            let normal = if cos_light > 0.0 { shading } else { -shading };
            let frame = SensorFrame::new(at, normal, self.bias);
            if let Some(lights) = &self.lights {
                radiance += beta * self.light_sample(&frame, lights, u.light, None, rays);
            }
            radiance += beta * self.sky_sample(&frame, u.sky, None, rays);
            let local = cosine_hemisphere(u.direction);
            p_cosine = local.z as f64 / PI;
            ray = Ray::new(frame.origin, frame.to_world(local));
        }
    }

    /// What the user should hear once about a render with these parameters: with global illumination, a
    /// material in use that absorbs no light in some channel (a `Kd` component ≥ 1) leaves the paths to
    /// roulette and the throughput cap.
    pub fn warnings(&self) -> Vec<String> {
        if self.params.indirect.bounces().is_none() {
            return Vec::new();
        }
        let mesh = &self.scene.mesh;
        let mut used: Vec<usize> = mesh.surfaces.iter().map(|s| s.material).collect();
        used.sort_unstable();
        used.dedup();
        let names: Vec<String> = used
            .iter()
            .map(|&m| &mesh.materials[m])
            .filter(|m| m.kd.max_element() >= 1.0)
            .map(|m| format!("'{}'", m.name))
            .collect();
        if names.is_empty() {
            return Vec::new();
        }
        let (noun, verb) = if names.len() == 1 { ("material", "has") } else { ("materials", "have") };
        vec![format!(
            "{noun} {} {verb} a Kd component ≥ 1, which absorbs no light: with global illumination the oracle's paths \
             through it end only by Russian roulette (survival ≤ {MAX_SURVIVAL} per bounce) or past a throughput of \
             {MAX_THROUGHPUT:e}; where such surfaces enclose a light there is no finite answer, and the estimate \
             is finite but not converged",
            names.join(", ")
        )]
    }
}
