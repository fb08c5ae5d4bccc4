//! One pixel's final gather, rasterized and ray cast: the GPU's R at the pixel (every pixel sensed) beside
//! a CPU gather over the same radiance cache (cosine directions, the cache looked up where each ray hits,
//! as the sensor maps do) plus the oracle's direct light there. Where the two differ, the sensor maps see
//! the cache differently from the rays; where they agree and the oracle does not, the cache is off.
//! `cargo run --release --example gather_probe -- SCENE.toml WIDTH HEIGHT X Y`

use anyhow::{Context as _, Result};
use glam::Vec3;
use sensorlight::params::{Bounces, EstimatorParams, FrameParams, Indirect};
use sensorlight::reference::integrator::Integrator;
use sensorlight::reference::sampling::{ScrambledSobol, cosine_hemisphere};
use sensorlight::renderer::{CacheConfig, Quiet, Renderer};
use sensorlight::scene::bvh::Bvh;
use sensorlight::scene::{ImageSize, Ray, Scene};
use sensorlight::sensors::SensorKind;
use sensorlight::sensors::frame::{self, SensorFrame};
use sensorlight::strategy::StrategyKind;
use sensorlight::vk::{Device, DeviceOptions};

fn main() -> Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let scene = Scene::load(std::path::Path::new(a.get(1).context("usage: SCENE W H X Y")?))?;
    let n = |i: usize| -> Result<u32> { Ok(a.get(i).context("usage: SCENE W H X Y")?.parse()?) };
    let (size, x, y) = (ImageSize { width: n(2)?, height: n(3)? }, n(4)?, n(5)?);
    let device = Device::new(&DeviceOptions::from_env(None, sensorlight::passes::requirements()))?;
    let indirect = Indirect::Bounces(Bounces::Converged);
    let frame = FrameParams::every_pixel(indirect, Vec3::ZERO);
    let mut renderer = Renderer::builder(&device, &scene, SensorKind::Hemicube, 32)
        .radiance_cache(Some(CacheConfig::new(
            std::env::var("RES").ok().and_then(|s| s.parse().ok()).unwrap_or(16),
            std::env::var("CRD").ok().and_then(|s| s.parse().ok()).unwrap_or(16),
        )))
        .build_unchecked(StrategyKind::Layered)?;
    renderer.solve_cache(&frame, &Quiet)?;
    // STEP > 0: every STEP-th pixel of the rows from Y on, summed (a region's bias, not one pixel's).
    let step: u32 = std::env::var("STEP").ok().and_then(|s| s.parse().ok()).unwrap_or(0);
    let pixels: Vec<u32> = if step == 0 {
        vec![y * size.width + x]
    } else {
        (y * size.width..size.width * size.height).step_by(step as usize).collect()
    };
    let g = renderer.gbuffer(size)?;
    let pixels: Vec<u32> = pixels.into_iter().filter(|&i| g.position[i as usize].w > 0.0).collect();
    let (gpu, _) = renderer.sense_at(size, &pixels, &frame)?;
    let values = renderer.cache_values()?;
    let cache = renderer.cache().context("a cache")?;
    let bvh = Bvh::build(&scene.mesh.triangles);
    let scale = scene.mesh.scale();
    let params = |indirect| EstimatorParams { sensor: SensorKind::Hemicube, indirect, background: Vec3::ZERO };
    let direct_oracle = Integrator::new(&scene, params(Indirect::Bounces(Bounces::Fixed(0))), 4096, 1)?;
    let full_oracle = Integrator::new(&scene, params(indirect), 16384, 1)?;
    let lum = |v: Vec3| v.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let (mut sums, mut noise) = ([0.0f64; 3], 0.0f64);
    for (k, &pixel) in pixels.iter().enumerate() {
        let (p, normal) = (g.position[pixel as usize].truncate(), g.normal[pixel as usize].truncate());
        let sensor = SensorFrame::new(p, normal, frame::BIAS * scale);
        let directions = ScrambledSobol::new(7 + pixel as u64);
        let count = 1 << 14;
        let mut rest = Vec3::ZERO;
        for i in 0..count {
            let d = sensor.to_world(cosine_hemisphere(directions.point(i)));
            if let Some(hit) = bvh.intersect(&Ray::new(sensor.origin, d), frame::NEAR * scale, f32::INFINITY) {
                let t = &scene.mesh.triangles[hit.triangle as usize];
                let q = sensor.origin + d * hit.t;
                let front = d.dot(t.normal) < 0.0;
                rest += values[cache.lookup_from(q, sensor.origin, t.surface, front)].truncate();
            }
        }
        rest /= count as f32;
        let direct = direct_oracle.radiance(p, normal, pixel as u64).mean;
        let full = full_oracle.radiance(p, normal, pixel as u64);
        let row = [lum(gpu[k].truncate()), lum(rest + direct), lum(full.mean)];
        if step == 0 {
            println!("pixel ({x}, {y}) at {p}, normal {normal}");
            println!(
                "GPU R {}, CPU gather over the cache + oracle direct {}, oracle {} ± {}",
                row[0],
                row[1],
                row[2],
                lum(full.std_error)
            );
        }
        (0..3).for_each(|j| sums[j] += row[j] as f64);
        noise += (lum(full.std_error) as f64).powi(2);
    }
    println!(
        "{} pixels: GPU / oracle {:.4}, CPU gather / oracle {:.4}, GPU / CPU gather {:.4} (oracle's relative noise of the sum {:.4})",
        pixels.len(),
        sums[0] / sums[2],
        sums[1] / sums[2],
        sums[0] / sums[1],
        noise.sqrt() / sums[2]
    );
    Ok(())
}
