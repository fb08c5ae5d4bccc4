//! A bright room seen through a slit narrower than a sensor's texel (docs/DESIGN.md §3 step 5): the slit
//! lands on whole texels of some sensors and on none of their neighbours', so pixel by pixel R is twice the
//! truth or a fraction of it. The sensors whose maps hold such a thin bright feature, and their sensed
//! neighbours, are sensed again at twice the rd (`renderer::fine`). Checked against a ray gather over the same
//! radiance cache at the same points, which sees the slit in proportion to its solid angle.

mod common;

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use sensorlight::params::{Bounces, FrameParams, Indirect};
use sensorlight::renderer::{CacheConfig, Quiet, Renderer};
use sensorlight::scene::bvh::Bvh;
use sensorlight::scene::camera::Camera;
use sensorlight::scene::{ImageSize, Ray, Scene};
use sensorlight::sensors::SensorKind;
use sensorlight::sensors::frame::{self, SensorFrame};
use sensorlight::strategy::StrategyKind;

/// Rays of the gather per pixel: the slit is ~1 % of a floor point's cosine-weighted hemisphere, so 65 536
/// rays leave ~4 % noise on what it sends.
const RAYS: u32 = 1 << 16;

/// The two rooms' shell, the dividing wall at x = 0 cut by a vertical slit 2.5 cm wide; the bright room
/// (x > 0) lit by a panel on its floor facing up, which no point of the dark room's floor sees: the dark
/// floor's light is all what it sees of the bright room through the slit.
fn slit_scene() -> Scene {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let slit = 0.025;
    let half = (1.0 - slit / 2.0) / 2.0;
    let mut groups = common::two_rooms_shell();
    groups.extend([
        (
            "wall",
            0,
            [common::rect(y + z * (1.0 - half), z * half, y, x), common::rect(y - z * (1.0 - half), z * half, y, x)]
                .concat(),
        ),
        ("light", 1, common::rect(Vec3::new(1.2, 0.01, 0.0), x * 0.3, z * 0.3, y)),
    ]);
    let materials = vec![common::material("white", 0.8, 0.0), common::material("light", 0.0, 100.0)];
    let camera = Camera::look_at(Vec3::new(-1.9, 1.4, 0.0), Vec3::new(-0.6, 0.0, 0.0), y, 70.0).unwrap();
    common::scene(groups, materials, camera, (40, 30))
}

/// Of the dark floor's pixels (every third), R as sensed beside R as a ray gather over the same cache: the
/// relative RMS of their difference and the gather's own noise, and the finer sensors the render took.
fn sensed_against_the_gather(scene: &Scene) -> (f64, f64, u64) {
    let size = ImageSize { width: scene.image.width, height: scene.image.height };
    let frame = FrameParams::every_pixel(Indirect::Bounces(Bounces::Converged), Vec3::ZERO);
    common::gpu(|device| {
        let mut renderer = Renderer::builder(device, scene, SensorKind::Hemicube, 32)
            .radiance_cache(Some(CacheConfig::new(16, 16)))
            .build_unchecked(StrategyKind::Layered)
            .unwrap();
        let out = renderer.render(size, &frame, &Quiet).unwrap();
        let (g, values) = (renderer.gbuffer(size).unwrap(), renderer.cache_values().unwrap());
        let cache = renderer.cache().unwrap();
        let bvh = Bvh::build(&scene.mesh.triangles);
        let scale = scene.mesh.scale();
        let floor: Vec<usize> = (0..g.position.len())
            .step_by(3)
            .filter(|&i| g.position[i].w > 0.0 && g.normal[i].y > 0.99 && g.position[i].x < -0.05)
            .collect();
        let gathered: Vec<(f64, f64, f64)> = floor
            .par_iter()
            .map(|&i| {
                let (p, n) = (g.position[i].truncate(), g.normal[i].truncate());
                let sensor = SensorFrame::new(p, n, frame::BIAS * scale);
                let (mut sum, mut squares) = (0.0f64, 0.0f64);
                for k in 0..RAYS {
                    // Stratified cosine directions (Malley), turned per pixel.
                    let u = (k as f32 + 0.5) / RAYS as f32;
                    let phi = std::f32::consts::TAU * (k as f32 * 0.618_034 + i as f32 * 0.754_877_7).fract();
                    let d = sensor.to_world(Vec3::new(u.sqrt() * phi.cos(), u.sqrt() * phi.sin(), (1.0 - u).sqrt()));
                    let ray = Ray::new(sensor.origin, d);
                    if let Some(hit) = bvh.intersect(&ray, frame::NEAR * scale, f32::INFINITY) {
                        let t = &scene.mesh.triangles[hit.triangle as usize];
                        let q = sensor.origin + d * hit.t;
                        let v = values[cache.lookup_from(q, sensor.origin, t.surface, d.dot(t.normal) < 0.0)];
                        let l = luminance(v) as f64;
                        sum += l;
                        squares += l * l;
                    }
                }
                let mean = sum / RAYS as f64;
                let noise = ((squares / RAYS as f64 - mean * mean).max(0.0) / RAYS as f64).sqrt();
                (luminance(out.radiance[i]) as f64, mean, noise)
            })
            .collect();
        let lit: Vec<&(f64, f64, f64)> = gathered.iter().filter(|(_, mean, _)| *mean > 0.0).collect();
        assert!(lit.len() > 40, "{} floor pixels see the slit", lit.len());
        let rms = |f: &dyn Fn(&(f64, f64, f64)) -> f64| {
            (lit.iter().map(|x| f(x).powi(2)).sum::<f64>() / lit.len() as f64).sqrt()
        };
        let error = rms(&|(sensed, mean, _)| (sensed - mean) / mean);
        let noise = rms(&|(_, mean, noise)| noise / mean);
        (error, noise, out.stats.fine_sensors)
    })
}

fn luminance(v: Vec4) -> f32 {
    v.truncate().dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// At rd 32 the slit is about half a texel wide to the dark floor's sensors: pixel by pixel 14.4 % off the
/// gather with the finer sensors off, 8.4 % with them (the gather's own noise 1.3 %).
#[test]
fn a_slit_narrower_than_a_texel_is_sensed_again_at_twice_the_rd() {
    let (error, noise, fine) = sensed_against_the_gather(&slit_scene());
    eprintln!("sensed against the gather: {error:.4} per pixel (the gather's noise {noise:.4}); {fine} finer sensors");
    assert!(error < 0.115, "sensed against the gather: {error:.4} per pixel (the gather's noise {noise:.4})");
    assert!(fine > 0, "no sensor was sensed again");
}
