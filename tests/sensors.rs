//! The GPU sensors (sensor maps + reduction) against the CPU reference and analytic answers.

mod common;

use glam::Vec3;
use sensorlight::gpu_types::radiance_state::SENSED;
use sensorlight::reference::integrator::Integrator;
use sensorlight::sensors::SensorKind;

const FRUSTUM: SensorKind = SensorKind::Frustum { fov_deg: 135.0 };

/// Agreement of GPU and CPU R at the GPU's visible points: (relative RMSE, relative RMSE of the reference's
/// own noise, relative RMSE with that noise removed = the GPU's own error).
fn agreement(kind: SensorKind, rd: u32, size: u32, samples: u32) -> (f64, f64, f64) {
    let scene = common::lightbox((size, size));
    let params = common::every_pixel(kind, rd, 0.1);
    let out = common::render(&scene, &params, None);
    let cpu = Integrator::new(&scene, params.estimator, samples, 3).unwrap();
    let g = &out.gbuffer;
    let (mut error2, mut noise2, mut signal2) = (0.0f64, 0.0f64, 0.0f64);
    for i in (0..g.position.len()).filter(|&i| g.position[i].w > 0.0) {
        assert_eq!(out.radiance[i].w, SENSED, "every visible pixel is sensed with dradiance 0");
        let reference = cpu.radiance(g.position[i].truncate(), g.normal[i].truncate(), i as u64);
        error2 += (out.radiance[i].truncate() - reference.mean).length_squared() as f64;
        noise2 += reference.std_error.length_squared() as f64;
        signal2 += reference.mean.length_squared() as f64;
    }
    let (rmse, noise) = ((error2 / signal2).sqrt(), (noise2 / signal2).sqrt());
    let own = ((error2 - noise2).max(0.0) / signal2).sqrt();
    eprintln!("{kind} rd {rd}: relative RMSE {rmse:.4}, reference noise {noise:.4}, GPU's own error {own:.4}");
    (rmse, noise, own)
}

/// What limits the agreement is the sensor map's point sampling at the light's silhouette: its error
/// falls like 1/rd, and a 135° frustum's central texels are 2.4× wider than a hemicube's, so it needs a
/// larger map for the same error (measured in the closing note of the sensor pipeline).
#[test]
fn hemicube_r_matches_the_cpu_reference_within_2_percent() {
    let (rmse, _, own) = agreement(SensorKind::Hemicube, 128, 64, 4096);
    assert!(own <= 0.02 && rmse <= 0.025, "GPU error {own}, RMSE {rmse}");
}

#[test]
fn frustum_r_matches_the_cpu_reference_within_2_percent() {
    let (rmse, _, own) = agreement(FRUSTUM, 256, 48, 4096);
    assert!(own <= 0.02 && rmse <= 0.025, "GPU error {own}, RMSE {rmse}");
}

#[test]
fn gpu_error_falls_as_the_sensor_map_grows() {
    let (_, _, coarse) = agreement(SensorKind::Hemicube, 32, 32, 2048);
    let (_, _, fine) = agreement(SensorKind::Hemicube, 128, 32, 2048);
    assert!(fine < coarse / 2.0, "rd 32: {coarse}, rd 128: {fine}");
}

#[test]
fn white_furnace_on_the_gpu() {
    let scene = common::furnace(2.0);
    for (kind, expected) in [(SensorKind::Hemicube, 2.0), (FRUSTUM, 0.8774 * 2.0)] {
        let out = common::render(&scene, &common::every_pixel(kind, 32, 0.25), None);
        let lit: Vec<Vec3> = out.radiance.iter().filter(|r| r.w == SENSED).map(|r| r.truncate()).collect();
        assert_eq!(lit.len(), (scene.image.width * scene.image.height) as usize);
        for r in lit {
            assert!(
                (r - Vec3::splat(expected)).abs().max_element() < 0.01 * expected,
                "{kind}: R {r}, expected {expected}"
            );
        }
    }
}

#[test]
fn batching_does_not_change_the_result() {
    // A budget of one sensor's maps forces a batch per sensor; the numbers must not move.
    let scene = common::lightbox((20, 16));
    let params = common::every_pixel(SensorKind::Hemicube, 16, 0.1);
    let one = common::render(&scene, &params, Some(1));
    let many = common::render(&scene, &params, None);
    assert_eq!(one.stats.batch_size, 1);
    assert!(one.stats.batches > many.stats.batches);
    assert_eq!(one.stats.sensors, many.stats.sensors);
    assert!(one.radiance == many.radiance, "R differs between batch sizes");
}

/// Where the device's queue writes timestamps, the device's time for sensor maps and reduction comes from
/// them: present, positive, and (one queue) within the wall time of the sensing phase.
#[test]
fn gpu_time_comes_from_timestamps_where_the_device_has_them() {
    let scene = common::lightbox((24, 16));
    let setup = common::every_pixel(SensorKind::Hemicube, 16, 0.1);
    common::gpu(|device| {
        let mut renderer = sensorlight::renderer::Renderer::builder(device, &scene, setup.estimator.sensor, setup.rd)
            .build_unchecked(Default::default())
            .unwrap();
        let t = renderer.render(scene.image, &setup.frame, &sensorlight::renderer::Quiet).unwrap().stats.times;
        if device.adapter.timestamp_valid_bits == 0 {
            assert!(t.gpu_maps_seconds.is_none() && t.gpu_reduction_seconds.is_none());
            return;
        }
        let (maps, reduction) = (t.gpu_maps_seconds.unwrap(), t.gpu_reduction_seconds.unwrap());
        assert!(maps > 0.0 && reduction > 0.0, "maps {maps} s, reduction {reduction} s");
        assert!(
            maps + reduction <= 1.05 * t.sensing_seconds,
            "GPU {maps} + {reduction} s > sensing {} s",
            t.sensing_seconds
        );
    });
}

/// Emission beyond the half-float maps' 65504 renders right with the paper's estimator (which writes `Ke`
/// into the maps): in a furnace of `Ke` every hemicube sees `R = Ke`, for any finite `Ke`, in the colour
/// given (before, `Ke` 1e5 rendered at 0.66 of its brightness, and its colour shifted).
#[test]
fn emission_beyond_half_float_range_renders_right() {
    use sensorlight::params::EstimatorKind;
    use sensorlight::renderer::{Quiet, Renderer};
    use sensorlight::strategy::StrategyKind;
    for ke in [1e5f32, 3e9, 1e18] {
        let mut scene = common::furnace(ke);
        scene.mesh.materials[0].ke = Vec3::new(ke, 0.5 * ke, 0.25 * ke);
        let setup = common::every_pixel(SensorKind::Hemicube, 16, 0.25);
        let out = common::gpu(|device| {
            let mut renderer = Renderer::builder(device, &scene, SensorKind::Hemicube, 16)
                .estimator(EstimatorKind::Paper)
                .build_unchecked(StrategyKind::default())
                .unwrap();
            renderer.render(scene.image, &setup.frame, &Quiet).unwrap()
        });
        let expected = Vec3::new(ke, 0.5 * ke, 0.25 * ke);
        for r in out.radiance.iter().filter(|r| r.w == SENSED) {
            let error = ((r.truncate() - expected) / expected).abs().max_element();
            assert!(error < 2e-3, "Ke {ke}: R {r}, expected {expected} (relative error {error:.1e})");
        }
    }
}
