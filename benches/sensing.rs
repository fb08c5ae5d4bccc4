//! Criterion benchmarks of the inner loops: sensing a batch on the GPU with each strategy that passes its
//! self-check, the texel weights, and the CPU reference's per-point integral. `cargo bench --bench sensing`.
//! For the strategy comparison with raw fill and spread, use `sensorlight bench` (docs/BENCHMARKS.md).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use sensorlight::passes::sensor_maps::StrategyKind;
use sensorlight::reference::integrator::Integrator;
use sensorlight::renderer::Renderer;
use sensorlight::sensors::{SensorKind, weights};
use sensorlight::strategy::{self, Probe};
use sensorlight::vk::{Device, DeviceOptions};

fn gpu_sensing(c: &mut Criterion) {
    let device = match Device::new(&DeviceOptions::default()) {
        Ok(d) => d,
        Err(e) => return eprintln!("no Vulkan device, GPU benchmarks skipped: {e:#}"),
    };
    let probe = Probe::new(64);
    let mut group = c.benchmark_group(format!("sense 64 hemicube sensors on {}", device.adapter.name));
    group.sample_size(10);
    for rd in [32, 128] {
        for kind in StrategyKind::ALL {
            match strategy::self_check(&device, SensorKind::Hemicube, kind) {
                Ok(check) if check.passed => {}
                _ => continue,
            }
            let mut renderer = Renderer::new(&device, &probe.scene, SensorKind::Hemicube, rd, None, kind).unwrap();
            group.bench_function(format!("{kind} rd {rd}"), |b| {
                b.iter(|| renderer.radiance_at(&probe.scene, probe.size, &probe.pixels, &probe.estimator).unwrap())
            });
        }
    }
    group.finish();
}

fn cpu_loops(c: &mut Criterion) {
    c.bench_function("hemicube weights rd 256", |b| {
        b.iter(|| weights::sensor_weights(black_box(SensorKind::Hemicube), 256))
    });
    let probe = Probe::new(1);
    let integrator = Integrator::new(&probe.scene, probe.estimator, 1024, 1).unwrap();
    c.bench_function("reference R at one point, 1024 directions", |b| {
        b.iter(|| integrator.radiance(black_box(Vec3::new(0.1, 0.0, 0.2)), Vec3::Y, 7))
    });
}

criterion_group!(benches, gpu_sensing, cpu_loops);
criterion_main!(benches);
