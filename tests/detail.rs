//! `Detail::Auto` measured (`renderer::detail`): a mesh of a few hundred triangles is drawn from its
//! clusters where they sense the scene's own pixels faster and alike, at full detail otherwise; the choice is
//! remembered; smaller meshes are not measured; larger ones are, full detail on a few sensors first.

mod common;

use sensorlight::renderer::detail::{CLEARLY_SLOWER, CLUSTER_GAIN, DETAIL_PROBE_MIN_TRIANGLES};
use sensorlight::renderer::{CLUSTER_MIN_TRIANGLES, Detail, Renderer};
use sensorlight::sensors::SensorKind;
use sensorlight::strategy::{CHECK_TOLERANCE, Cache};

#[test]
fn auto_detail_is_measured_on_mid_sized_meshes_and_remembered() {
    let scene = common::sphere_by_a_wall((32, 24));
    let triangles = scene.mesh.triangles.len();
    assert!((DETAIL_PROBE_MIN_TRIANGLES..CLUSTER_MIN_TRIANGLES).contains(&triangles), "{triangles}");
    let small = common::lightbox((32, 24));
    common::gpu(|device| {
        let mut cache = Cache::in_memory();
        let build = |scene, cache: &mut Cache| {
            Renderer::builder(device, scene, SensorKind::Hemicube, 32).cache(cache).build().unwrap()
        };
        let first = build(&scene, &mut cache);
        let probe = first.detail_probe().expect("a mesh of a few hundred triangles is measured").clone();
        let (full, clusters) = probe.times.expect("measured now");
        let difference = probe.difference.unwrap();
        // The choice follows the rule, whichever way this machine's timings fall.
        let faster = full.as_secs_f64() >= CLUSTER_GAIN * clusters.as_secs_f64();
        let expected = faster && difference <= CHECK_TOLERANCE;
        assert_eq!(probe.detail == Detail::Clusters, expected, "{probe:?}");
        assert_eq!(first.culled(), expected, "the renderer draws as measured");
        assert!(difference <= CHECK_TOLERANCE, "clusters of a 528-triangle sphere draw as full detail: {difference}");
        drop(first);
        let second = build(&scene, &mut cache);
        let again = second.detail_probe().unwrap();
        assert_eq!((again.detail, again.times), (probe.detail, None), "remembered, not measured again");
        assert_eq!(second.culled(), expected);
        drop(second);
        let box_only = build(&small, &mut cache);
        assert!(box_only.detail_probe().is_none() && !box_only.culled(), "a box is drawn whole, unmeasured");
    });
}

/// A mesh past the old fixed threshold (a 6 240-triangle sphere) is measured too, not drawn from its
/// clusters by its count: the clusters are kept by the same rule, where full detail on a few sensors was
/// already [`CLEARLY_SLOWER`] times slower than the gain asks, or slower on them all.
#[test]
fn auto_detail_is_measured_on_large_meshes_too() {
    let scene = common::sphere_by_a_wall_of((32, 24), 40);
    let triangles = scene.mesh.triangles.len();
    assert!(triangles > CLUSTER_MIN_TRIANGLES, "{triangles}");
    common::gpu(|device| {
        let mut cache = Cache::in_memory();
        let renderer = Renderer::builder(device, &scene, SensorKind::Hemicube, 32).cache(&mut cache).build().unwrap();
        let probe = renderer.detail_probe().expect("a large mesh is measured").clone();
        let (full, clusters) = probe.times.expect("measured now");
        let difference = probe.difference.unwrap();
        let expected = full.as_secs_f64() >= CLUSTER_GAIN * clusters.as_secs_f64() && difference <= CHECK_TOLERANCE;
        assert_eq!(probe.detail == Detail::Clusters, expected, "{probe:?}");
        assert_eq!(renderer.culled(), expected, "the renderer draws as measured");
        assert!(difference <= CHECK_TOLERANCE, "clusters of a 6 240-triangle sphere draw as full detail: {difference}");
        eprintln!(
            "{triangles} triangles: {probe:?} (decided early where full ≥ {} × clusters)",
            CLEARLY_SLOWER * CLUSTER_GAIN
        );
    });
}
