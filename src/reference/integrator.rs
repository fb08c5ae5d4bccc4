//! The estimator of docs/DESIGN.md §1 by ray casting:
//!
//! `R(p) = (1/π) ∫ Ck(ray(p, ω)) cosθ dω`, `Ck = Ke` on the front of an emitter, `Kd·ε` elsewhere,
//! the background where the ray leaves the scene; pixel = `Le + Kd·R`.
//!
//! Directions are cosine-distributed, so `R` is the plain mean of `Ck` over them. The domain is the sensor's:
//! the whole hemisphere (hemicube) or the paper's square frustum, turned by the same [`SensorFrame`] as the
//! GPU sensor (directions outside it count 0). Rays leave from the sensor's origin `p + n·bias` and, like
//! the GPU views with their near plane, do not see geometry closer than [`frame::NEAR`] (relative to the
//! scene): a point on the seam of two walls then sees the room, not the back of the other wall at 1e-8.
//!
//! Noise estimate: the samples are split into [`REPLICATES`] independently scrambled Sobol nets; the spread
//! of their means gives an unbiased standard error of the estimate (randomised quasi-Monte Carlo).

use anyhow::{Result, ensure};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::bvh::Bvh;
use super::gbuffer;
use super::sampling::{ScrambledSobol, cosine_hemisphere, hash};
use crate::gbuffer::GBufferData;
use crate::params::EstimatorParams;
use crate::scene::{ImageSize, Ray, Scene};
use crate::sensors::{SensorKind, frame};

/// Independent scrambles per point; their spread measures the noise.
pub const REPLICATES: u32 = 4;

pub struct Integrator<'a> {
    scene: &'a Scene,
    bvh: Bvh,
    params: EstimatorParams,
    /// Directions per point, split evenly over the replicates.
    samples: u32,
    seed: u64,
    bias: f32,
    near: f32,
    /// Half-width of the frustum on the plane z = 1; `None` for the whole hemisphere.
    frustum: Option<f32>,
}

/// `R` at one point with its standard error (per channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub mean: Vec3,
    pub std_error: Vec3,
}

pub struct ReferenceImage {
    pub gbuffer: GBufferData,
    /// R per pixel (rgb; w = 1 where a surface is seen).
    pub radiance: Vec<Vec4>,
    pub std_error: Vec<Vec4>,
    /// `Le + Kd·R`.
    pub image: Vec<Vec4>,
    /// Rays cast, primary ones included.
    pub rays: u64,
}

impl<'a> Integrator<'a> {
    /// `samples`: directions per point, a multiple of [`REPLICATES`] (powers of two stratify best).
    pub fn new(scene: &'a Scene, params: EstimatorParams, samples: u32, seed: u64) -> Result<Self> {
        ensure!(
            samples >= REPLICATES && samples.is_multiple_of(REPLICATES),
            "--samples must be a positive multiple of {REPLICATES}, got {samples}"
        );
        let frustum = match params.sensor {
            SensorKind::Frustum { fov_deg } => Some((fov_deg.to_radians() * 0.5).tan()),
            SensorKind::Hemicube => None,
        };
        Ok(Self {
            bvh: Bvh::build(&scene.mesh.triangles),
            bias: frame::BIAS * scene.mesh.scale(),
            near: frame::NEAR * scene.mesh.scale(),
            scene,
            params,
            samples,
            seed,
            frustum,
        })
    }

    /// `Ck` of the first surface along the unit-direction `ray` beyond the near distance (paper §III-C).
    pub fn ck(&self, ray: &Ray) -> Vec3 {
        let Some(hit) = self.bvh.intersect(ray, self.near, f32::INFINITY) else { return self.params.background };
        let tri = &self.scene.mesh.triangles[hit.triangle as usize];
        let material = self.scene.mesh.material_of(tri.surface);
        let front = ray.dir.dot(tri.normal) < 0.0;
        if front && material.is_emitter() { material.ke } else { material.kd * self.params.epsilon }
    }

    /// `R` at the surface point `p` with unit normal `n` (facing the viewer). `key` picks the scramble, e.g.
    /// the pixel index: equal keys give equal results.
    pub fn radiance(&self, p: Vec3, n: Vec3, key: u64) -> Estimate {
        let sensor = frame::SensorFrame::new(p, n, self.bias);
        let per_replicate = self.samples / REPLICATES;
        let mut means = [Vec3::ZERO; REPLICATES as usize];
        for (r, mean) in means.iter_mut().enumerate() {
            let net = ScrambledSobol::new(hash(self.seed ^ hash(key)) ^ r as u64);
            let mut sum = Vec3::ZERO;
            for i in 0..per_replicate {
                let local = cosine_hemisphere(net.point(i));
                if let Some(s) = self.frustum
                    && (local.x.abs() > s * local.z || local.y.abs() > s * local.z)
                {
                    continue; // outside the paper's square view: the sensor does not see it
                }
                sum += self.ck(&Ray::new(sensor.origin, sensor.to_world(local)));
            }
            *mean = sum / per_replicate as f32;
        }
        let mean = means.iter().sum::<Vec3>() / REPLICATES as f32;
        let variance = means.iter().map(|m| (*m - mean) * (*m - mean)).sum::<Vec3>() / (REPLICATES - 1) as f32;
        Estimate { mean, std_error: (variance / REPLICATES as f32).map(f32::sqrt) }
    }

    /// The reference image at `size`: visible points by ray casting, `R` at each, `Le + Kd·R`.
    /// `progress` is called with the number of rows finished, from worker threads.
    pub fn render(&self, size: ImageSize, progress: &(dyn Fn(u64) + Sync)) -> ReferenceImage {
        let g = gbuffer::cast(self.scene, &self.bvh, size);
        let width = size.width as usize;
        let estimates: Vec<Option<Estimate>> = (0..size.height as usize)
            .into_par_iter()
            .flat_map_iter(|y| {
                let row: Vec<_> = (y * width..(y + 1) * width)
                    .map(|i| {
                        let (p, n) = (g.position[i], g.normal[i]);
                        (p.w > 0.0).then(|| self.radiance(p.truncate(), n.truncate(), i as u64))
                    })
                    .collect();
                progress(1);
                row
            })
            .collect();
        let lit = estimates.iter().filter(|e| e.is_some()).count() as u64;
        let radiance: Vec<Vec4> = estimates.iter().map(|e| e.map_or(Vec4::ZERO, |e| e.mean.extend(1.0))).collect();
        let std_error = estimates.iter().map(|e| e.map_or(Vec4::ZERO, |e| e.std_error.extend(1.0))).collect();
        let image = super::post::compose(&g, &radiance);
        let rays = g.position.len() as u64 + lit * self.samples as u64;
        ReferenceImage { gbuffer: g, radiance, std_error, image, rays }
    }
}

impl ReferenceImage {
    /// Mean relative standard error of `R` over the pixels where `R` is not negligible (luminance-weighted).
    pub fn relative_noise(&self) -> f32 {
        let lum = |v: Vec4| v.truncate().dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let peak = self.radiance.iter().map(|&r| lum(r)).fold(0.0, f32::max);
        let (sum, count) = self
            .radiance
            .iter()
            .zip(&self.std_error)
            .filter(|(r, _)| lum(**r) > 1e-3 * peak)
            .fold((0.0, 0), |(s, c), (r, e)| (s + lum(*e) / lum(*r), c + 1));
        if count == 0 { 0.0 } else { sum / count as f32 }
    }
}
