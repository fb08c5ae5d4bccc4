//! Global illumination on the GPU (docs/DESIGN.md §10) against closed forms: the closed box of uniform
//! emission `Le` and albedo ρ (`L = Le/(1 − ρ)`, and `Le·(1 + ρ + … + ρ^{N+1})` after N bounces), a plane
//! under a white sky, and a thin wall with light on one side only.

mod common;

use glam::Vec3;
use sensorlight::params::{Bounces, FrameParams, Indirect};
use sensorlight::renderer::{CacheConfig, Quiet, RenderOutput, Renderer};
use sensorlight::scene::{Camera, Scene};
use sensorlight::sensors::SensorKind;
use sensorlight::strategy::StrategyKind;

/// Renders `scene` with global illumination (`bounces`), every pixel sensed, hemicube rd `rd`, the cache at
/// `resolution`.
fn render_gi(scene: &Scene, bounces: Bounces, background: Vec3, (rd, resolution): (u32, u32)) -> RenderOutput {
    let frame = FrameParams::every_pixel(Indirect::Bounces(bounces), background);
    common::gpu(|device| {
        let mut renderer = Renderer::builder(device, scene, SensorKind::Hemicube, rd)
            .radiance_cache(Some(CacheConfig::new(resolution, 16)))
            .build_unchecked(StrategyKind::default())
            .unwrap();
        renderer.render(scene.image, &frame, &Quiet).unwrap()
    })
}

/// A closed cube whose every face emits `ke` inwards and reflects `kd`.
fn closed_box(kd: f32, ke: f32) -> Scene {
    let mut s = common::furnace(ke);
    s.mesh.materials[0].kd = Vec3::splat(kd);
    s
}

/// The mean and the largest relative deviation of every pixel's luminance from `expected`.
fn deviation(out: &RenderOutput, expected: f32) -> (f32, f32) {
    let lum: Vec<f32> = out.image.iter().map(|p| p.truncate().dot(Vec3::new(0.2126, 0.7152, 0.0722))).collect();
    let mean = lum.iter().sum::<f32>() / lum.len() as f32;
    let worst = lum.iter().map(|l| ((l - expected) / expected).abs()).fold(0.0, f32::max);
    ((mean - expected) / expected, worst)
}

/// `L = Le/(1 − ρ)` everywhere: ρ 0.5 converges in a few bounces, ρ 0.9 (the hard one: 1 % would take 40
/// plain bounces) through the extrapolated tail.
#[test]
fn the_closed_box_converges_to_le_over_one_minus_rho() {
    for rho in [0.5f32, 0.9] {
        let le = 2.0;
        let scene = closed_box(rho, le);
        let out = render_gi(&scene, Bounces::Converged, Vec3::ZERO, (16, 4));
        let gi = out.stats.gi.as_ref().unwrap();
        let (mean, worst) = deviation(&out, le / (1.0 - rho));
        eprintln!("ρ {rho}: mean {mean:+.5}, worst {worst:.5}, {} bounces, tail {:.3}", gi.bounces, gi.tail_share);
        assert!(mean.abs() < 5e-3 && worst < 5e-3, "ρ {rho}: mean {mean:+.4}, worst pixel {worst:.4}");
        assert!(gi.bounces <= 8, "ρ {rho}: {} bounces", gi.bounces);
    }
}

/// After N bounces exactly the first N + 2 terms of the series (no tail): the oracle's `--bounces N`.
#[test]
fn fixed_bounces_sum_the_series_exactly() {
    let (rho, le) = (0.6f32, 1.0);
    let scene = closed_box(rho, le);
    for n in [0u32, 1, 2] {
        let out = render_gi(&scene, Bounces::Fixed(n), Vec3::ZERO, (16, 4));
        let expected: f32 = (0..=n + 1).map(|k| rho.powi(k as i32)).sum::<f32>() * le;
        let (mean, worst) = deviation(&out, expected);
        assert!(mean.abs() < 2e-3 && worst < 2e-3, "{n} bounces: mean {mean:+.4}, worst {worst:.4} of {expected}");
        assert_eq!(out.stats.gi.as_ref().map_or(0, |g| g.bounces), n);
    }
}

/// A floor under a white sky, nothing else: it sees the sky and nothing of itself, so `L = Kd·1`.
#[test]
fn a_plane_under_the_sky_reflects_the_sky() {
    let kd = 0.6;
    let floor = common::rect(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, Vec3::Y);
    let camera = Camera::look_at(Vec3::new(0.0, 1.5, 1.5), Vec3::ZERO, Vec3::Y, 40.0).unwrap();
    let scene = common::scene(vec![("floor", 0, floor)], vec![common::material("grey", kd, 0.0)], camera, (16, 16));
    let out = render_gi(&scene, Bounces::Converged, Vec3::ONE, (16, 8));
    let seen: Vec<f32> =
        (out.image.iter().zip(&out.gbuffer.position)).filter(|(_, p)| p.w > 0.0).map(|(c, _)| c.x).collect();
    assert!(!seen.is_empty());
    for c in seen {
        assert!((c - kd).abs() < 1e-3 * kd, "{c} against {kd}");
    }
}

/// Two rooms under one floor and one ceiling, divided by a wall (zero thickness, or 2 cm, both thinner than
/// a cache cell), a light in one: the other stays dark, to the last bit of every bounce.
#[test]
fn light_does_not_cross_a_thin_wall() {
    for thickness in [0.0f32, 0.02] {
        let scene = common::two_rooms(thickness, (24, 24));
        let out = render_gi(&scene, Bounces::Converged, Vec3::ZERO, (16, 8));
        let dark = out.image.iter().zip(&out.gbuffer.position).filter(|(_, p)| p.w > 0.0 && p.x < -1e-3);
        let brightest = dark.map(|(c, _)| c.truncate().max_element()).fold(0.0, f32::max);
        assert!(brightest == 0.0, "thickness {thickness}: a pixel of the dark room is {brightest}");
        // The lit room is lit: the same camera turned to it.
        let mut lit = scene.clone();
        lit.camera = Camera::look_at(Vec3::new(1.8, 1.5, 0.8), Vec3::new(0.0, 0.3, -0.3), Vec3::Y, 70.0).unwrap();
        let out = render_gi(&lit, Bounces::Converged, Vec3::ZERO, (16, 8));
        let seen = out.image.iter().zip(&out.gbuffer.position).filter(|(_, p)| p.w > 0.0 && p.x > 1e-3);
        assert!(seen.map(|(c, _)| c.x).fold(f32::INFINITY, f32::min) > 0.0, "every pixel of the lit room is lit");
    }
}

/// The closed box's bounces show in the statistics: entries, keys, bounces, the last change.
#[test]
fn the_statistics_report_the_cache() {
    let out = render_gi(&closed_box(0.5, 1.0), Bounces::Converged, Vec3::ZERO, (16, 4));
    let gi = out.stats.gi.unwrap();
    assert!(gi.entries >= 12 && gi.entries.is_multiple_of(2), "{} entries: both sides of every piece", gi.entries);
    assert!(gi.keys >= gi.entries / 2 && gi.cache_bytes > 0);
    assert!(gi.last_change.unwrap() < sensorlight::gi::solve::DEFAULT_TOLERANCE);
    assert!((gi.ratio.unwrap() - 0.5).abs() < 0.01, "λ of a box of albedo 0.5: {:?}", gi.ratio);
}
