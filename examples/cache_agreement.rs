//! The radiance cache against the oracle at its own points (docs/DESIGN.md §10): after the bounces, each
//! entry's reflected radiance `Kd·R` beside the path tracer's at the same point and side; the relative RMSE
//! and bias over the lit entries, all and split by a plane (e.g. the two rooms of the door ajar).
//! `cargo run --release --example cache_agreement -- SCENE.toml [SAMPLES] [AXIS VALUE]`; `RES=N`: the cache's
//! cells along the longest side (default 16); `MEAN=1`: the oracle's mean over each piece's spread points
//! (what an entry holds where its light varies), not at its sensor's point; `LIT=S`: entries count as lit
//! above S of the brightest (default 0.001); `DETAIL=SURFACE`: that surface's entries above the plane, the
//! `TOP=N` (default 20) that weigh most in its bias.

use anyhow::{Context as _, Result};
use glam::Vec3;
use sensorlight::params::{Bounces, EstimatorParams, FrameParams, Indirect};
use sensorlight::reference::integrator::Integrator;
use sensorlight::renderer::{CacheConfig, Quiet, Renderer};
use sensorlight::scene::Scene;
use sensorlight::sensors::SensorKind;
use sensorlight::strategy::StrategyKind;
use sensorlight::vk::{Device, DeviceOptions};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::load(std::path::Path::new(args.get(1).context("usage: SCENE.toml [SAMPLES] [AXIS VALUE]")?))?;
    let samples: u32 = args.get(2).map_or(Ok(1024), |s| s.parse())?;
    let split: Option<(usize, f32)> = match (args.get(3), args.get(4)) {
        (Some(a), Some(v)) => Some((a.parse()?, v.parse()?)),
        _ => None,
    };
    let device = Device::new(&DeviceOptions::from_env(None, sensorlight::passes::requirements()))?;
    // CACHE_BOUNCES=N: the cache after N bounces against the oracle's R with N − 1 (the cache's bounce k
    // holds the light of k − 1 bounces before the entry's own reflection).
    let bounces: Option<u32> = std::env::var("CACHE_BOUNCES").ok().and_then(|b| b.parse().ok());
    let indirect = Indirect::Bounces(bounces.map_or(Bounces::Converged, Bounces::Fixed));
    let oracle_indirect = Indirect::Bounces(bounces.map_or(Bounces::Converged, |n| Bounces::Fixed(n - 1)));
    let frame = FrameParams::every_pixel(indirect, Vec3::ZERO);
    let res = std::env::var("RES").ok().and_then(|s| s.parse().ok()).unwrap_or(16);
    let cache = CacheConfig::new(res, 16);
    let mut renderer = Renderer::builder(&device, &scene, SensorKind::Hemicube, 32)
        .radiance_cache(Some(cache))
        .build_unchecked(StrategyKind::Layered)?;
    let stats = renderer.solve_cache(&frame, &Quiet)?.context("a cache")?;
    println!("{} entries, {} bounces", stats.entries, stats.bounces);
    let values = renderer.cache_values()?;
    let c = renderer.cache().context("a cache")?;
    let params = EstimatorParams { sensor: SensorKind::Hemicube, indirect: oracle_indirect, background: Vec3::ZERO };
    let oracle = Integrator::new(&scene, params, samples, 3)?;
    let mean = std::env::var("MEAN").is_ok_and(|m| m == "1");
    let lum = |v: Vec3| v.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let rows: Vec<(f32, f32, f32, Vec3, u32)> = (c.entries.iter().enumerate())
        .map(|(i, e)| {
            // MEAN=1: the oracle's mean over the piece's spread points (what a piece's entry holds).
            let r = if mean {
                let side = if e.front { 1.0 } else { -1.0 };
                let at = &c.points[i / 2];
                (at.iter().enumerate())
                    .map(|(k, &(p, n))| oracle.radiance(p, n * side, (i * 8 + k) as u64).mean)
                    .sum::<Vec3>()
                    / at.len() as f32
            } else {
                oracle.radiance(e.point, e.normal, i as u64).mean
            };
            (lum(values[i].truncate()), lum(c.albedo[i] * r), e.area, e.point, e.surface)
        })
        .collect();
    let lit_share: f32 = std::env::var("LIT").ok().and_then(|l| l.parse().ok()).unwrap_or(1e-3);
    let peak = rows.iter().map(|r| r.1).fold(0.0, f32::max);
    let report = |name: &str, keep: &dyn Fn(Vec3) -> bool| {
        let lit: Vec<_> = rows.iter().filter(|r| r.1 > lit_share * peak && keep(r.3)).collect();
        let rel: Vec<f64> = lit.iter().map(|r| ((r.0 - r.1) / r.1) as f64).collect();
        let rmse = (rel.iter().map(|e| e * e).sum::<f64>() / rel.len().max(1) as f64).sqrt();
        let (a, b) = lit.iter().fold((0.0, 0.0), |(a, b), r| (a + (r.0 * r.2) as f64, b + (r.1 * r.2) as f64));
        println!("{name}: {} lit entries, relative RMSE {rmse:.4}, area-weighted bias {:+.4}", lit.len(), a / b - 1.0);
    };
    report("all", &|_| true);
    if let Some((axis, value)) = split {
        report("below", &|p| p[axis] < value);
        report("above", &|p| p[axis] >= value);
        // Per surface, above the plane.
        let mut surfaces: Vec<u32> = rows.iter().map(|r| r.4).collect();
        surfaces.sort_unstable();
        surfaces.dedup();
        for s in surfaces {
            let lit: Vec<_> =
                rows.iter().filter(|r| r.4 == s && r.3[axis] >= value && r.1 > lit_share * peak).collect();
            if lit.len() < 4 {
                continue;
            }
            let (a, b) = lit.iter().fold((0.0, 0.0), |(a, b), r| (a + (r.0 * r.2) as f64, b + (r.1 * r.2) as f64));
            println!("  surface {s}: {} entries above, area-weighted bias {:+.4}", lit.len(), a / b - 1.0);
            if std::env::var("DETAIL").is_ok_and(|d| d == s.to_string()) {
                let mut worst = lit.clone();
                worst.sort_by(|x, y| ((y.0 - y.1) * y.2).abs().total_cmp(&((x.0 - x.1) * x.2).abs()));
                let top = std::env::var("TOP").ok().and_then(|t| t.parse().ok()).unwrap_or(20);
                for r in worst.iter().take(top) {
                    println!(
                        "    at {:.2?}: cache {:.4} oracle {:.4} area {:.4} ({:+.0} %)",
                        r.3,
                        r.0,
                        r.1,
                        r.2,
                        100.0 * (r.0 / r.1 - 1.0)
                    );
                }
            }
        }
    }
    Ok(())
}
