//! Criterion benchmarks of the inner loops: sensing a batch on the GPU with each strategy that passes its
//! self-check, the texel weights, and the CPU reference's per-point integral. `cargo bench --bench sensing`.
//! For the strategy comparison with raw fill and spread, use `sensorlight bench` (docs/BENCHMARKS.md).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use sensorlight::params::{EstimatorKind, EstimatorParams, FrameParams, Indirect};
use sensorlight::reference::integrator::Integrator;
use sensorlight::renderer::{self, Renderer, probe_pixels};
use sensorlight::scene::{ImageSize, builtin};
use sensorlight::sensors::{SensorKind, weights};
use sensorlight::strategy::StrategyKind;
use sensorlight::vk::{Device, DeviceOptions};

fn gpu_sensing(c: &mut Criterion) {
    let options = DeviceOptions { requirements: sensorlight::passes::requirements(), ..Default::default() };
    let device = match Device::new(&options) {
        Ok(d) => d,
        Err(e) => return eprintln!("no Vulkan device, GPU benchmarks skipped: {e:#}"),
    };
    let size = ImageSize { width: 32, height: 32 };
    let scene = builtin::lightbox(size);
    let frame = FrameParams::every_pixel(Indirect::Epsilon(0.2), Vec3::splat(0.05));
    let mut group = c.benchmark_group(format!("sense 64 hemicube sensors on {}", device.adapter.name));
    group.sample_size(10);
    for rd in [32, 128] {
        for kind in StrategyKind::ALL {
            match renderer::self_check(&device, SensorKind::Hemicube, EstimatorKind::Exact, kind) {
                Ok(check) if check.passed => {}
                _ => continue,
            }
            let mut renderer =
                Renderer::builder(&device, &scene, SensorKind::Hemicube, rd).build_unchecked(kind).unwrap();
            let pixels = probe_pixels(&renderer.gbuffer(size).unwrap().surface, 64);
            group.bench_function(format!("{kind} rd {rd}"), |b| {
                b.iter(|| renderer.sense_at(size, &pixels, &frame).unwrap())
            });
        }
    }
    group.finish();
}

fn cpu_loops(c: &mut Criterion) {
    c.bench_function("hemicube weights rd 256", |b| {
        b.iter(|| weights::sensor_weights(black_box(SensorKind::Hemicube), 256))
    });
    let scene = builtin::lightbox(ImageSize { width: 32, height: 32 });
    let estimator = EstimatorParams {
        sensor: SensorKind::Hemicube,
        indirect: Indirect::Epsilon(0.2),
        background: Vec3::splat(0.05),
    };
    let integrator = Integrator::new(&scene, estimator, 1024, 1).unwrap();
    c.bench_function("reference R at one point, 1024 directions", |b| {
        b.iter(|| integrator.radiance(black_box(Vec3::new(0.1, 0.0, 0.2)), Vec3::Y, 7))
    });
}

criterion_group!(benches, gpu_sensing, cpu_loops);
criterion_main!(benches);
