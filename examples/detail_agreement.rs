//! R at the same sensors drawn at full detail and from the clusters (docs/DESIGN.md §9): relative RMSE over
//! the lit sensors, and time per sensor of each.
//! `cargo run --release --example detail_agreement -- SCENE.toml [SENSORS] [RD]`

use anyhow::{Context as _, Result};
use sensorlight::params::{EstimatorKind, FrameParams};
use sensorlight::renderer::{Detail, Renderer, probe_pixels};
use sensorlight::scene::{ImageSize, Scene};
use sensorlight::sensors::SensorKind;
use sensorlight::strategy::StrategyKind;
use sensorlight::vk::{Device, DeviceOptions};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::load(std::path::Path::new(args.get(1).context("usage: SCENE.toml [SENSORS] [RD]")?))?;
    let sensors: usize = args.get(2).map_or(Ok(64), |s| s.parse())?;
    let rd: u32 = args.get(3).map_or(Ok(64), |s| s.parse())?;
    let device = Device::new(&DeviceOptions::from_env(None, sensorlight::passes::requirements()))?;
    let size = ImageSize { width: 128, height: 128 };
    let frame = FrameParams::every_pixel(sensorlight::params::Indirect::Epsilon(0.1), glam::Vec3::ZERO);
    let mut r = Vec::new();
    for detail in [Detail::Full, Detail::Clusters] {
        let mut renderer = Renderer::builder(&device, &scene, SensorKind::Hemicube, rd)
            .estimator(EstimatorKind::Exact)
            .detail(detail)
            .build_unchecked(StrategyKind::Layered)?;
        let pixels = probe_pixels(&renderer.gbuffer(size)?.surface, sensors);
        let (values, time) = renderer.sense_at(size, &pixels, &frame)?;
        println!(
            "{detail:?}: {} sensors, {:.2} ms/sensor",
            pixels.len(),
            1e3 * time.as_secs_f64() / pixels.len() as f64
        );
        r.push(values);
    }
    let lum = |v: glam::Vec4| 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z;
    let brightest = r[0].iter().map(|&v| lum(v)).fold(0.0, f32::max);
    let lit: Vec<f64> = r[0]
        .iter()
        .zip(&r[1])
        .filter(|(f, _)| lum(**f) > 1e-3 * brightest)
        .map(|(&f, &c)| ((lum(c) - lum(f)) / lum(f)) as f64)
        .collect();
    let rmse = (lit.iter().map(|e| e * e).sum::<f64>() / lit.len().max(1) as f64).sqrt();
    println!(
        "R, clusters against full detail: relative RMSE {rmse:.5} over {} lit sensors of {}",
        lit.len(),
        r[0].len()
    );
    Ok(())
}
