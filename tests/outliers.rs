//! No pixel of the shipped scenes lies far outside its neighbours' range unless the oracle's does too
//! (issue 24's outliers: single bright or dark pixels, docs/ACCURACY.md "Outlier pixels").

mod common;

use glam::Vec4;
use sensorlight::gbuffer::GBufferData;
use sensorlight::params::Indirect;
use sensorlight::reference::integrator::Integrator;
use sensorlight::renderer::{CacheConfig, Quiet, Renderer};
use sensorlight::scene::{ImageSize, NO_SURFACE, Scene};

/// A pixel is an outlier when its luminance is above `(1 + F)×` the brightest of its 8 neighbours or below
/// their darkest `/ (1 + F)`, by more than `ABSOLUTE` of the image's mean, all nine on one surface and none
/// an emitter (silhouettes and lights are judged by other tests), and not supersampled (an edge, a light's
/// rim, a sliver: the whole-image tests of `tests/supersample.rs` judge those).
const F: f32 = 0.5;
const ABSOLUTE: f32 = 0.05;

fn luminance(p: Vec4) -> f32 {
    0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z
}

/// The outliers of `image` over `g`, as pixel indices, by the rule above with factor `f`, but for the
/// `supersampled` pixels (increasing).
fn outliers(image: &[Vec4], g: &GBufferData, supersampled: &[u32], f: f32) -> Vec<usize> {
    let (w, h) = (g.size.width as usize, g.size.height as usize);
    let lit: Vec<f32> = image.iter().map(|&p| luminance(p)).collect();
    let mean = lit.iter().sum::<f32>() / lit.len() as f32;
    let mut found = Vec::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let window: Vec<usize> = (0..9).map(|k| (y + k / 3 - 1) * w + x + k % 3 - 1).collect();
            let uniform =
                window.iter().all(|&j| g.surface[j] == g.surface[i] && g.emission[j].truncate().max_element() == 0.0);
            if !uniform || g.surface[i] == NO_SURFACE || supersampled.binary_search(&(i as u32)).is_ok() {
                continue;
            }
            let others = window.iter().filter(|&&j| j != i).map(|&j| lit[j]);
            let (lo, hi) = others.fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
            let margin = ABSOLUTE * mean;
            if lit[i] > (1.0 + f) * hi + margin || lit[i] < lo / (1.0 + f) - margin {
                found.push(i);
            }
        }
    }
    found
}

/// Each shipped scene at 64 × 48 with its defaults (global illumination on the small scenes; direct light
/// on the room and the door ajar, whose caches cost a minute here): any outlier must be one in the oracle
/// too (256 samples, with half the factor for its noise), which is rendered only when there is a candidate.
#[test]
fn no_pixel_of_the_shipped_scenes_is_an_outlier_the_oracle_does_not_share() {
    let size = ImageSize { width: 64, height: 48 };
    for (file, gi) in [
        ("scenes/cornell/cornell.toml", true),
        ("scenes/cornell-mcguire/cornell-mcguire.toml", true),
        ("scenes/small-light/small-light.toml", true),
        ("scenes/room/room.toml", false),
        ("scenes/door-ajar/door-ajar.toml", false),
    ] {
        let path = common::project(file);
        let scene = Scene::load(&path).unwrap();
        let table = sensorlight::params::Overrides::from_scene_table(&path, &scene.render).unwrap();
        let mut p = sensorlight::params::RenderParams::resolve(Some((&path, &table)), &Default::default()).unwrap();
        if !gi {
            p.estimator.indirect = Indirect::Epsilon(0.0);
        }
        let out = common::gpu(|device| {
            Renderer::builder(device, &scene, p.estimator.sensor, p.values.sensor_size)
                .estimator(p.values.estimator)
                .radiance_cache(CacheConfig::for_params(&p))
                .build_unchecked(Default::default())
                .unwrap()
                .render(size, &p.frame(), &Quiet)
                .unwrap()
        });
        let candidates = outliers(&out.image, &out.gbuffer, &out.supersampled, F);
        eprintln!("{file}: {} candidate outlier(s)", candidates.len());
        if candidates.is_empty() {
            continue;
        }
        let oracle = Integrator::new(&scene, p.estimator, 256, 3).unwrap().render(size, p.values.aa, &|_| ());
        let shared = outliers(&oracle.image, &oracle.gbuffer, &[], F / 2.0);
        let unexplained: Vec<_> = candidates.iter().filter(|i| !shared.contains(i)).collect();
        assert!(unexplained.is_empty(), "{file}: outliers the oracle does not share at pixels {unexplained:?}");
    }
}
