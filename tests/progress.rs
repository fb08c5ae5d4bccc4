//! What a render tells its `Progress`: phases in order, pixels resolved that only grow to the whole image,
//! and snapshots that are the image so far (the last one the final image when nothing filters it).

mod common;

use std::cell::RefCell;

use glam::Vec4;
use sensorlight::params::FrameParams;
use sensorlight::renderer::{Phase, Progress, Renderer, RoundDone, Snapshot};
use sensorlight::sensors::SensorKind;
use sensorlight::strategy::StrategyKind;

#[derive(Default)]
struct Recorder {
    phases: RefCell<Vec<Phase>>,
    rounds: RefCell<Vec<RoundDone>>,
    snapshots: RefCell<Vec<(u32, Vec<Vec4>)>>,
    queued: RefCell<u64>,
    done: RefCell<u64>,
}

impl Progress for Recorder {
    fn phase(&self, phase: Phase) {
        self.phases.borrow_mut().push(phase);
    }
    fn queued(&self, n: u64) {
        *self.queued.borrow_mut() += n;
    }
    fn done(&self, n: u64) {
        *self.done.borrow_mut() += n;
    }
    fn round(&self, round: &RoundDone) {
        self.rounds.borrow_mut().push(*round);
    }
    fn wants_snapshot(&self, _round: u32) -> bool {
        true
    }
    fn snapshot(&self, snapshot: &Snapshot) {
        let pixels = (snapshot.size.width * snapshot.size.height) as usize;
        assert_eq!(snapshot.image.len(), pixels);
        self.snapshots.borrow_mut().push((snapshot.round, snapshot.image.clone()));
    }
}

#[test]
fn progress_sees_every_phase_round_and_snapshot() {
    let scene = common::lightbox((48, 40));
    let frame = FrameParams {
        indirect: sensorlight::params::Indirect::Epsilon(0.1),
        background: glam::Vec3::ZERO,
        tile: 8,
        dradiance: 0.2,
        filter_radius: 0,
        indirect_filter_radius: 0,
        // The previews are of the pixel centres; the final image's supersampled edges are not previewed.
        aa: sensorlight::params::Antialiasing::Off,
        region: None,
    };
    let recorder = Recorder::default();
    let output = common::gpu(|device| {
        let mut renderer = Renderer::builder(device, &scene, SensorKind::Hemicube, 16)
            .build_unchecked(StrategyKind::default())
            .unwrap();
        renderer.render(scene.image, &frame, &recorder).unwrap()
    });
    assert_eq!(*recorder.phases.borrow(), [Phase::GBuffer, Phase::Sensing, Phase::Post]);
    let (queued, done) = (*recorder.queued.borrow(), *recorder.done.borrow());
    assert_eq!((queued, done), (output.stats.sensors, output.stats.sensors), "every sensor queued and done");

    let rounds = recorder.rounds.borrow();
    let pixels = 48 * 40;
    assert!(rounds.len() >= 2, "a refining render has several rounds: {rounds:?}");
    assert!(rounds.windows(2).all(|w| w[0].resolved_pixels <= w[1].resolved_pixels), "never refills: {rounds:?}");
    assert!(rounds.iter().all(|r| r.pixels == pixels && r.resolved_pixels <= pixels));
    assert_eq!(rounds.last().unwrap().resolved_pixels, pixels, "all resolved at the end");
    let per_round: Vec<u64> = rounds.iter().map(|r| r.sensors).filter(|&n| n > 0).collect();
    assert_eq!(per_round, output.stats.sensors_per_round, "a report per sensing round");

    // One snapshot per sensing round; the last one, unfiltered like the render here, is the final image.
    let snapshots = recorder.snapshots.borrow();
    let numbers: Vec<u32> = snapshots.iter().map(|s| s.0).collect();
    assert_eq!(numbers, (1..=output.stats.sensors_per_round.len() as u32).collect::<Vec<_>>());
    let last = &snapshots.last().unwrap().1;
    let peak = output.image.iter().map(|p| p.truncate().max_element()).fold(0.0, f32::max);
    for (i, (a, b)) in last.iter().zip(&output.image).enumerate() {
        let d = (a.truncate() - b.truncate()).abs().max_element();
        assert!(d <= 1e-4 * peak, "pixel {i}: snapshot {a} vs final {b}");
    }
    // The first snapshot is already a whole image: lit wherever the final one is.
    let first = &snapshots[0].1;
    let lit = |img: &[Vec4]| img.iter().filter(|p| p.truncate().max_element() > 0.0).count();
    assert!(lit(first) * 10 >= lit(&output.image) * 9, "first preview lit {} of {}", lit(first), lit(&output.image));
}

/// With global illumination under a lit background, the radiance cache's sky pass is part of its first
/// bounce: no sensor is reported done before it was queued, and every one queued is done (the display's
/// count of a bounce once ran past its total).
#[test]
fn the_cache_never_reports_more_sensors_done_than_queued() {
    #[derive(Default)]
    struct Counts {
        queued: RefCell<u64>,
        done: RefCell<u64>,
        overrun: RefCell<bool>,
    }
    impl Progress for Counts {
        fn queued(&self, n: u64) {
            *self.queued.borrow_mut() += n;
        }
        fn done(&self, n: u64) {
            *self.done.borrow_mut() += n;
            *self.overrun.borrow_mut() |= *self.done.borrow() > *self.queued.borrow();
        }
    }
    let scene = common::lightbox((24, 20));
    let indirect = sensorlight::params::Indirect::Bounces(sensorlight::params::Bounces::Fixed(2));
    let frame = FrameParams { tile: 8, dradiance: 0.2, ..FrameParams::every_pixel(indirect, glam::Vec3::splat(0.3)) };
    let counts = Counts::default();
    let output = common::gpu(|device| {
        let cache = sensorlight::renderer::CacheConfig::new(4, 8);
        let mut renderer = Renderer::builder(device, &scene, SensorKind::Hemicube, 16)
            .radiance_cache(Some(cache))
            .build_unchecked(StrategyKind::default())
            .unwrap();
        renderer.render(scene.image, &frame, &counts).unwrap()
    });
    let gi = output.stats.gi.as_ref().expect("a radiance cache");
    assert!(!*counts.overrun.borrow(), "more sensors done than queued at some point");
    let (queued, done) = (*counts.queued.borrow(), *counts.done.borrow());
    assert_eq!(queued, done, "every sensor queued is done");
    // The camera's sensors, and the cache's: each entry light reaches once (its rows say what it sees of
    // the constant sky too).
    let cache = gi.reached + gi.spread_sensors;
    assert_eq!(done, output.stats.sensors + cache, "every sensor is counted: {done}");
}
