//! The exact estimator's emitter term (docs/DESIGN.md §2): where nothing occludes a light, the visibility
//! read from its zoom pair is exactly 1 and R is the light's irradiance in closed form, so the GPU's R must
//! equal the CPU twin (`light::polygon`, in f64) at every pixel, for both sensor kinds and at any map size.

mod common;

use glam::{DVec3, Vec3};
use sensorlight::gpu_types::radiance_state::SENSED;
use sensorlight::light::polygon::{Domain, Receiver, projected_solid_angle};
use sensorlight::params::EstimatorKind;
use sensorlight::reference::lights::LUMINANCE;
use sensorlight::renderer::{Quiet, Renderer};
use sensorlight::scene::{Camera, Scene};
use sensorlight::sensors::SensorKind;
use sensorlight::sensors::frame::{self, SensorFrame};

/// A floor under two lights and beside a third, nothing else: a square facing down, a tilted triangle, and
/// a wall light standing on the floor whose foot lies at every floor sensor's horizon.
fn open_floor() -> Scene {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let square = common::rect(Vec3::new(-0.3, 1.2, 0.2), x * 0.25, z * 0.2, -y);
    let tilted = vec![[Vec3::new(0.6, 1.5, -0.4), Vec3::new(0.9, 1.0, -0.5), Vec3::new(0.4, 1.3, 0.3)]];
    let wall = common::rect(Vec3::new(1.4, 0.4, 0.0), z * 0.5, y * 0.4, -x);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 1.5), Vec3::ZERO, y, 60.0).unwrap();
    let materials = vec![
        common::material("floor", 0.6, 0.0),
        common::material("lamp", 0.5, 3.0),
        common::material("warm", 0.5, 7.0),
        common::material("wall lamp", 0.5, 1.5),
    ];
    let groups = vec![
        ("floor", 0, common::rect(Vec3::ZERO, x * 2.0, z * 2.0, y)),
        ("square", 1, square),
        ("tilted", 2, tilted),
        ("wall", 3, wall),
    ];
    common::scene(groups, materials, camera, (40, 32))
}

/// Rec. 709 luminance, as the oracle weighs its lights.
fn luminance(c: Vec3) -> f64 {
    c.dot(LUMINANCE) as f64
}

/// R by the closed form at the sensor of every surface pixel (none for the background).
fn closed_form(scene: &Scene, sensor: SensorKind, position: &[glam::Vec4], normal: &[glam::Vec4]) -> Vec<Option<f64>> {
    let domain = match sensor {
        SensorKind::Hemicube => Domain::Hemisphere,
        SensorKind::Frustum { fov_deg } => Domain::Frustum { half_width: (fov_deg as f64 / 2.0).to_radians().tan() },
    };
    let bias = frame::BIAS * scene.mesh.scale();
    position
        .iter()
        .zip(normal)
        .map(|(p, n)| {
            (p.w > 0.0).then(|| {
                let f = SensorFrame::new(p.truncate(), n.truncate(), bias);
                let receiver =
                    Receiver { origin: f.origin.as_dvec3(), t: f.t.as_dvec3(), b: f.b.as_dvec3(), n: f.n.as_dvec3() };
                let mesh = &scene.mesh;
                mesh.triangles
                    .iter()
                    .filter(|t| mesh.material_of(t.surface).is_emitter())
                    .map(|t| {
                        let polygon: Vec<DVec3> = t.v.iter().map(|v| v.as_dvec3()).collect();
                        luminance(mesh.material_of(t.surface).ke) * projected_solid_angle(&receiver, domain, &polygon)
                    })
                    .sum::<f64>()
                    / std::f64::consts::PI
            })
        })
        .collect()
}

fn agrees_with_the_closed_form(sensor: SensorKind, rd: u32) {
    let scene = open_floor();
    let setup = common::every_pixel(sensor, rd, 0.0);
    let out = common::gpu(|device| {
        let mut renderer = Renderer::builder(device, &scene, sensor, rd)
            .estimator(EstimatorKind::Exact)
            .build_unchecked(Default::default())
            .unwrap();
        renderer.render(scene.image, &setup.frame, &Quiet).unwrap()
    });
    let g = &out.gbuffer;
    let expected = closed_form(&scene, sensor, &g.position, &g.normal);
    let (mut worst, mut compared) = (0.0f64, 0);
    for (i, e) in expected.iter().enumerate() {
        let Some(e) = e else { continue };
        let r = out.radiance[i];
        assert_eq!(r.w, SENSED, "pixel {i} is sensed");
        if *e > 1e-3 && g.emission[i].truncate().max_element() == 0.0 {
            worst = worst.max((luminance(r.truncate()) - e).abs() / e);
            compared += 1;
        }
    }
    eprintln!("{sensor}, rd {rd}: worst relative difference {worst:.2e} over {compared} lit floor pixels");
    assert!(compared > 500, "the floor is lit: {compared} pixels");
    // f32 against f64: 2.3e-5 measured on lavapipe (the shader brings its own atan, see polygon.glsl).
    assert!(worst < 1e-4, "{sensor}, rd {rd}: R differs from the closed form by {worst:.2e}");
}

#[test]
fn unoccluded_light_is_exact_on_a_hemicube_at_any_map_size() {
    agrees_with_the_closed_form(SensorKind::Hemicube, 8);
    agrees_with_the_closed_form(SensorKind::Hemicube, 32);
}

#[test]
fn unoccluded_light_is_exact_on_a_frustum_whose_edge_cuts_the_lights() {
    agrees_with_the_closed_form(SensorKind::Frustum { fov_deg: 90.0 }, 16);
}

/// A light panel of 10 000 emissive triangles (a 50 × 100 grid) over a floor: every triangle is summed
/// exactly (the emitter pass takes them in chunks of 256 per sensor), so R equals the closed form as for
/// one quad, and the panel in one piece gives the same R. The cost of the 10 000 against the 2 is printed
/// (docs/ACCURACY.md), not asserted.
#[test]
fn ten_thousand_emissive_triangles_are_summed_exactly() {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let panel = |n: usize, m: usize| -> Vec<[Vec3; 3]> {
        let corner = Vec3::new(-0.5, 1.2, -0.25);
        let (du, dv) = (x * (1.0 / n as f32), z * (0.5 / m as f32));
        (0..n * m)
            .flat_map(|k| {
                let p = corner + du * (k % n) as f32 + dv * (k / n) as f32;
                // Counter-clockwise seen from below: the panel faces down ((x × z) = −y).
                [[p, p + du, p + dv], [p + du, p + du + dv, p + dv]]
            })
            .collect()
    };
    // Below the panel, looking at the floor under it.
    let camera = Camera::look_at(Vec3::new(0.0, 0.9, 1.6), Vec3::new(0.0, 0.0, 0.2), y, 60.0).unwrap();
    let materials = vec![common::material("floor", 0.6, 0.0), common::material("panel", 0.5, 4.0)];
    let render = |tris: Vec<[Vec3; 3]>, estimator| {
        let groups = vec![("floor", 0, common::rect(Vec3::ZERO, x * 2.0, z * 2.0, y)), ("panel", 1, tris)];
        let scene = common::scene(groups, materials.clone(), camera, (12, 10));
        let setup = common::every_pixel(SensorKind::Hemicube, 16, 0.0);
        let out = common::gpu(|device| {
            let mut renderer = Renderer::builder(device, &scene, SensorKind::Hemicube, 16)
                .estimator(estimator)
                .build_unchecked(Default::default())
                .unwrap();
            renderer.render(scene.image, &setup.frame, &Quiet).unwrap()
        });
        (scene, out)
    };
    let (many_scene, many) = render(panel(50, 100), EstimatorKind::Exact);
    assert_eq!(many_scene.mesh.triangles.iter().filter(|t| t.surface != 1).count(), 10_000, "the panel");
    let (_, one) = render(panel(1, 1), EstimatorKind::Exact);
    let (_, rasterized) = render(panel(50, 100), EstimatorKind::Paper);
    let g = &many.gbuffer;
    let expected = closed_form(&many_scene, SensorKind::Hemicube, &g.position, &g.normal);
    let mut worst = (0.0f64, 0.0f64);
    let mut compared = 0;
    for (i, e) in expected.iter().enumerate() {
        let Some(e) = e else { continue };
        if *e <= 1e-3 || g.emission[i].truncate().max_element() > 0.0 {
            continue;
        }
        let (many_r, one_r) = (luminance(many.radiance[i].truncate()), luminance(one.radiance[i].truncate()));
        worst.0 = worst.0.max((many_r - e).abs() / e);
        worst.1 = worst.1.max((one_r - many_r).abs() / e);
        compared += 1;
    }
    let per_sensor = |s: &sensorlight::renderer::RenderStats| s.times.sensing_seconds / s.sensors as f64 * 1e3;
    eprintln!(
        "10 000 emitters: worst {:.2e} from the closed form, {:.2e} from the panel in one piece, over {compared} \
         pixels; sensing {:.3} ms per sensor against {:.3} ms for 2 emitters ({:.3} ms with the paper's \
         estimator: drawing them alone)",
        worst.0,
        worst.1,
        per_sensor(&many.stats),
        per_sensor(&one.stats),
        per_sensor(&rasterized.stats)
    );
    assert!(compared > 60, "the floor is lit: {compared} pixels");
    assert!(worst.0 < 2e-4 && worst.1 < 2e-4, "{worst:?}");
}
