//! Sensor placement and adaptive refinement (paper §III-G), and the GPU interpolation that fills the quads.

mod common;

use glam::{Vec3, Vec4};
use sensorlight::gbuffer::GBufferData;
use sensorlight::gpu_types::GpuQuad;
use sensorlight::gpu_types::MAX_GROUPS;
use sensorlight::gpu_types::radiance_state::{INTERPOLATED, SENSED};
use sensorlight::light::groups::Lights;
use sensorlight::passes::interpolate::{Exact, InterpolatePass};
use sensorlight::reference::sampling::hash;
use sensorlight::scene::{Camera, ImageSize, NO_SURFACE};
use sensorlight::sensors::SensorKind;
use sensorlight::sensors::refine::{Refinement, Visibility, interpolate_cpu, interpolate_exact_cpu};
use sensorlight::vk::{Access, barrier, transfer};

/// A synthetic G-buffer: every pixel a surface (ids from `id`), all facing +z.
fn gbuffer(width: u32, height: u32, id: impl Fn(u32, u32) -> u32) -> GBufferData {
    let n = (width * height) as usize;
    let surface: Vec<u32> = (0..n as u32).map(|i| id(i % width, i / width)).collect();
    GBufferData {
        size: ImageSize { width, height },
        position: surface.iter().map(|&s| Vec4::new(0.0, 0.0, 0.0, if s == NO_SURFACE { 0.0 } else { 1.0 })).collect(),
        normal: vec![Vec4::new(0.0, 0.0, 1.0, 1.0); n],
        albedo: vec![Vec4::ONE; n],
        emission: vec![Vec4::ZERO; n],
        surface,
    }
}

/// Runs the refinement with "sensing" that returns `r(x, y)`; returns the sensed mask and the quads.
fn refine(g: &GBufferData, tile: u32, dradiance: f32, r: impl Fn(u32, u32) -> f32) -> (Vec<bool>, Vec<GpuQuad>) {
    refine_seeing(g, tile, dradiance, r, None)
}

/// [`refine`] where each sensor also sees a light group with visibility `v(x, y)`.
fn refine_seeing(
    g: &GBufferData,
    tile: u32,
    dradiance: f32,
    r: impl Fn(u32, u32) -> f32,
    v: Option<&dyn Fn(u32, u32) -> f32>,
) -> (Vec<bool>, Vec<GpuQuad>) {
    let w = g.size.width;
    let mut radiance = vec![Vec4::ZERO; g.surface.len()];
    let mut visibility: Vec<Visibility> =
        if v.is_some() { vec![[-1.0; MAX_GROUPS]; g.surface.len()] } else { Vec::new() };
    let (mut refinement, mut pending) = Refinement::start(g, tile, dradiance);
    loop {
        for &i in &pending {
            radiance[i as usize] = Vec3::splat(r(i % w, i / w)).extend(SENSED);
            if let Some(v) = v {
                visibility[i as usize][0] = v(i % w, i / w);
            }
        }
        if refinement.is_finished() {
            break;
        }
        pending = refinement.step(&radiance, &visibility, &[]);
    }
    let sensed = (0..g.surface.len()).map(|i| refinement.is_sensed(i)).collect();
    (sensed, refinement.interpolated().to_vec())
}

#[test]
fn dradiance_zero_senses_every_surface_pixel() {
    let g = gbuffer(37, 21, |x, y| if (x + y) % 11 == 0 { NO_SURFACE } else { 1 });
    let (sensed, quads) = refine(&g, 8, 0.0, |_, _| 0.5);
    for (i, &s) in sensed.iter().enumerate() {
        assert_eq!(s, g.surface[i] != NO_SURFACE, "pixel {i}");
    }
    assert!(quads.is_empty() || quads.iter().all(|q| q.x1 - q.x0 <= 1 && q.y1 - q.y0 <= 1));
}

#[test]
fn huge_dradiance_on_one_surface_senses_only_the_grid() {
    let g = gbuffer(37, 21, |_, _| 1);
    let (sensed, quads) = refine(&g, 8, 1e30, |x, y| (x * 7 + y * 3) as f32);
    let on_grid = |v: u32, n: u32| v.is_multiple_of(8) || v == n - 1;
    for (i, &s) in sensed.iter().enumerate() {
        let (x, y) = (i as u32 % 37, i as u32 / 37);
        assert_eq!(s, on_grid(x, 37) && on_grid(y, 21), "pixel ({x}, {y})");
    }
    // The quads tile the image exactly: every pixel is owned by one quad.
    let mut owners = vec![0; 37 * 21];
    for q in &quads {
        for y in q.y0..=q.own_y1 {
            for x in q.x0..=q.own_x1 {
                owners[(y * 37 + x) as usize] += 1;
            }
        }
    }
    assert!(owners.iter().all(|&o| o == 1), "quads overlap or leave gaps");
}

#[test]
fn no_quad_is_interpolated_across_a_surface_boundary() {
    // A diagonal boundary, a small island that falls between grid points, and background.
    let id = |x: u32, y: u32| {
        if (20..23).contains(&x) && (5..7).contains(&y) {
            3
        } else if x > 2 * y + 3 {
            1
        } else if x == 0 {
            NO_SURFACE
        } else {
            2
        }
    };
    let g = gbuffer(48, 24, id);
    let (sensed, quads) = refine(&g, 16, 1e30, |_, _| 1.0);
    assert!(!quads.is_empty());
    for q in &quads {
        let first = id(q.x0, q.y0);
        for y in q.y0..=q.y1 {
            for x in q.x0..=q.x1 {
                assert_eq!(id(x, y), first, "quad {q:?} spans surfaces");
            }
        }
    }
    // The island was found although no grid point lies on it.
    assert!((20..23).any(|x| (5..7).any(|y| sensed[(y * 48 + x) as usize])));
}

#[test]
fn variation_decides_between_interpolating_and_splitting() {
    // R jumps across x = 20: quads straddling it split, quads away from it interpolate.
    let g = gbuffer(65, 17, |_, _| 1);
    let (sensed, quads) = refine(&g, 16, 0.1, |x, _| if x < 20 { 1.0 } else { 2.0 });
    assert!(quads.iter().any(|q| q.x1 <= 16 && q.x1 - q.x0 == 16), "the flat left quad is interpolated whole");
    assert!(sensed[(8 * 65 + 19) as usize] || sensed[(8 * 65 + 20) as usize], "the jump is resolved to the pixel");
    assert!(!quads.iter().any(|q| q.x0 < 20 && q.x1 >= 20 && q.x1 - q.x0 > 1), "no interpolation across the jump");
}

/// A small light's shadow among brighter light: R varies less than dradiance across it, but the light's
/// visibility does, and the quads across the shadow's edge are split to the pixel.
#[test]
fn a_change_in_what_a_light_group_shows_splits_a_quad_even_where_r_is_flat() {
    let g = gbuffer(65, 17, |_, _| 1);
    let flat = |_, _| 1.0;
    let shadow = |x: u32, _: u32| if x < 20 { 1.0 } else { 0.2 };
    let (_, blind) = refine(&g, 16, 0.1, flat);
    assert!(blind.iter().any(|q| q.x0 < 20 && q.x1 > 20 && q.x1 - q.x0 == 16), "R alone interpolates across");
    let (sensed, quads) = refine_seeing(&g, 16, 0.1, flat, Some(&shadow));
    assert!(!quads.iter().any(|q| q.x0 < 20 && q.x1 >= 20 && q.x1 - q.x0 > 1), "no quad across the shadow's edge");
    assert!(sensed[(8 * 65 + 19) as usize] || sensed[(8 * 65 + 20) as usize], "the edge is sensed to the pixel");
    // A group no corner sees (−1) does not split anything.
    let (_, unseen) = refine_seeing(&g, 16, 0.1, flat, Some(&|_, _| -1.0));
    assert_eq!(unseen.len(), blind.len());
}

/// The GPU interpolation of `quads` over the radiance map and its indirect part (`maps`), with `exact` if
/// given; both maps as the pass leaves them.
fn gpu_interpolate(
    device: &std::sync::Arc<sensorlight::vk::Device>,
    size: ImageSize,
    quads: &[GpuQuad],
    maps: [&[Vec4]; 2],
    exact: Option<Exact<'_>>,
) -> [Vec<Vec4>; 2] {
    let usage = ash::vk::BufferUsageFlags::STORAGE_BUFFER | ash::vk::BufferUsageFlags::TRANSFER_SRC;
    let buffers = maps.map(|m| transfer::upload(device, "map", m, usage).unwrap());
    let mut pass = InterpolatePass::new(device).unwrap();
    pass.bind(device, quads, [&buffers[0], &buffers[1]], exact).unwrap();
    device
        .submit_and_wait(|enc| {
            barrier::global(enc, &[Access::TransferWrite], &[Access::ComputeWrite]);
            pass.record(enc, size);
            Ok(())
        })
        .unwrap();
    buffers.map(|b| transfer::read_buffer::<Vec4>(device, &b, (size.width * size.height) as usize).unwrap())
}

#[test]
fn gpu_interpolation_matches_the_cpu_twin() {
    let (w, h) = (45u32, 29u32);
    let g = gbuffer(w, h, |x, y| 1 + (x / 20) + 2 * (y / 13));
    let value = |x: u32, y: u32| {
        let k = hash((y * w + x) as u64);
        Vec3::new((k & 0xff) as f32, ((k >> 8) & 0xff) as f32, ((k >> 16) & 0xff) as f32) / 255.0
    };
    let (sensed, quads) = refine(&g, 8, 1e30, |_, _| 1.0);
    let initial: Vec<Vec4> =
        (0..w * h).map(|i| if sensed[i as usize] { value(i % w, i / w).extend(SENSED) } else { Vec4::ZERO }).collect();
    // The indirect map: other values, interpolated over the same quads.
    let other: Vec<Vec4> = initial.iter().map(|v| Vec4::new(v.z * 0.5, v.y * 0.25, v.x, v.w)).collect();
    let (mut expected, mut expected_other) = (initial.clone(), other.clone());
    interpolate_cpu(&mut expected, w, &quads);
    interpolate_cpu(&mut expected_other, w, &quads);
    assert!(expected.iter().any(|r| r.w == INTERPOLATED));
    let size = ImageSize { width: w, height: h };
    let got = common::gpu(|device| gpu_interpolate(device, size, &quads, [&initial, &other], None));
    for (got, expected) in got.iter().zip([&expected, &expected_other]) {
        for (i, (a, b)) in got.iter().zip(expected).enumerate() {
            assert_eq!(a.w, b.w, "state of pixel {i}");
            assert!((*a - *b).abs().max_element() <= 1e-6, "pixel {i}: GPU {a}, CPU {b}");
        }
    }
}

/// The exact interpolation (each light group's unoccluded light computed per pixel, its visibility and the
/// rest interpolated) against its CPU twin, on the small-light scene's real G-buffer with arbitrary corner
/// values: visibilities in [0, 1], some corners not measuring the group (−1), rests of any colour.
#[test]
fn gpu_exact_interpolation_matches_the_cpu_twin() {
    let (w, h) = (40u32, 30u32);
    let scene = common::small_light((w, h));
    let size = ImageSize { width: w, height: h };
    let bias = 2e-4 * scene.mesh.scale();
    let noise = |i: u32, salt: u64| hash(i as u64 ^ (salt << 40)) as f32 / u64::MAX as f32;
    let (g, initial, indirect, quads, corners, got) = common::gpu(|device| {
        let (gpu_scene, gbuffer, g) = common::raster_gbuffer(device, &scene, size);
        let (mut refinement, mut pending) = Refinement::start(&g, 8, 1e30);
        let mut sensed = vec![false; (w * h) as usize];
        while !refinement.is_finished() {
            pending.iter().for_each(|&i| sensed[i as usize] = true);
            pending = refinement.step(&vec![Vec4::ONE; (w * h) as usize], &[], &[]);
        }
        pending.iter().for_each(|&i| sensed[i as usize] = true);
        let quads = refinement.interpolated().to_vec();
        let value = |i: u32, salt| Vec3::new(noise(i, salt), noise(i, salt + 1), noise(i, salt + 2));
        let at = |i: u32, salt| if sensed[i as usize] { value(i, salt).extend(SENSED) } else { Vec4::ZERO };
        let initial: Vec<Vec4> = (0..w * h).map(|i| at(i, 1)).collect();
        let indirect: Vec<Vec4> = (0..w * h).map(|i| at(i, 5)).collect();
        let visibility = |i: u32| -> Visibility {
            let v = noise(i, 9);
            std::array::from_fn(|k| if k == 0 && v > 0.2 { v } else { -1.0 })
        };
        let corners: Vec<[Visibility; 4]> = quads
            .iter()
            .map(|q| [(q.x0, q.y0), (q.x1, q.y0), (q.x0, q.y1), (q.x1, q.y1)].map(|(x, y)| visibility(y * w + x)))
            .collect();
        let is_sensed = |i: usize| sensed[i];
        let exact =
            Exact { sensed: &is_sensed, corner_visibility: &corners, gbuffer: &gbuffer, scene: &gpu_scene, bias };
        let [got, _] = gpu_interpolate(device, size, &quads, [&initial, &indirect], Some(exact));
        (g, initial, indirect, quads, corners, got)
    });
    let mut expected = initial.clone();
    let lights = Lights::new(&scene.mesh);
    interpolate_exact_cpu((&mut expected, &indirect), &corners, (&g, &lights, bias), &quads);
    let lit = expected.iter().zip(&initial).filter(|(e, i)| e.w == INTERPOLATED && e.truncate() != i.truncate());
    assert!(lit.count() > 100, "the quads fill pixels");
    for (i, (a, b)) in got.iter().zip(&expected).enumerate() {
        assert_eq!(a.w, b.w, "state of pixel {i}");
        assert!((*a - *b).abs().max_element() <= 1e-4 * b.max_element().max(1.0), "pixel {i}: GPU {a}, CPU {b}");
    }
}

/// End to end on the GPU: two coplanar surfaces meeting along a slanted line; even with a huge dradiance,
/// every pixel next to the boundary is sensed, not interpolated.
#[test]
fn rendered_boundary_pixels_are_sensed() {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    // The plane z = 0 split along the line from (0.7, -2) to (-0.3, 2): `a` left of it, `b` right.
    let p = |x: f32, y: f32| Vec3::new(x, y, 0.0);
    let a = vec![[p(-2.0, -2.0), p(0.7, -2.0), p(-0.3, 2.0)], [p(-2.0, -2.0), p(-0.3, 2.0), p(-2.0, 2.0)]];
    let b = vec![[p(0.7, -2.0), p(2.0, -2.0), p(2.0, 2.0)], [p(0.7, -2.0), p(2.0, 2.0), p(-0.3, 2.0)]];
    let light = common::rect(Vec3::new(0.0, 0.0, 3.0), x, y, -z);
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, y, 60.0).unwrap();
    let materials =
        vec![common::material("a", 0.5, 0.0), common::material("b", 0.5, 0.0), common::material("lamp", 0.0, 1.0)];
    let scene = common::scene(vec![("a", 0, a), ("b", 1, b), ("lamp", 2, light)], materials, camera, (40, 40));
    let mut params = common::every_pixel(SensorKind::Hemicube, 8, 0.0);
    params.frame.tile = 8;
    params.frame.dradiance = 1e30;
    let out = common::render(&scene, &params, None);
    let ids = &out.gbuffer.surface;
    let distinct: std::collections::BTreeSet<_> = ids.iter().collect();
    assert_eq!(distinct.len(), 2, "both surfaces fill the view");
    let (w, h) = (40i64, 40i64);
    for i in 0..(w * h) {
        let (px, py) = (i % w, i / w);
        let next_to_boundary = (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                let (qx, qy) = (px + dx, py + dy);
                qx >= 0 && qy >= 0 && qx < w && qy < h && ids[(qy * w + qx) as usize] != ids[i as usize]
            })
        });
        if next_to_boundary {
            assert_eq!(out.radiance[i as usize].w, SENSED, "pixel ({px}, {py}) beside the boundary");
        }
    }
    assert!(out.stats.sensors < (w * h) as u64 / 2, "away from the boundary the grid is interpolated");
}

/// A floor lit at a grazing angle by a light standing at its edge, nothing occluding: R falls off steeply
/// and curves between any two sensed pixels, yet with the exact estimator an interpolated pixel is what a
/// sensor there finds (its light computed per pixel, only the visibility, 1 everywhere, interpolated).
/// Everything is interpolated from a 16-pixel grid; bilinear interpolation of R over the same quads is more
/// than 2 % off, the exact interpolation within 0.01 % of every pixel sensed.
#[test]
fn an_unoccluded_grazing_light_is_exact_between_sensors() {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let groups = vec![
        ("floor", 0, common::rect(Vec3::ZERO, x, z, y)),
        ("light", 1, common::rect(Vec3::new(-1.05, 0.1, 0.0), y * 0.05, z * 0.5, x)),
    ];
    let camera = Camera::look_at(Vec3::new(0.0, 2.2, 1.6), Vec3::ZERO, Vec3::Y, 45.0).unwrap();
    let materials = vec![common::material("grey", 0.5, 0.0), common::material("light", 0.0, 20.0)];
    let scene = common::scene(groups, materials, camera, (48, 48));
    let every = common::every_pixel(SensorKind::Hemicube, 16, 0.0);
    let mut coarse = every;
    (coarse.frame.tile, coarse.frame.dradiance) = (16, 1e30);
    let (truth, got) = (common::render(&scene, &every, None), common::render(&scene, &coarse, None));
    let floor: Vec<usize> = (0..truth.radiance.len()).filter(|&i| got.gbuffer.surface[i] == 1).collect();
    let interpolated = floor.iter().filter(|&&i| got.radiance[i].w == INTERPOLATED).count();
    assert!(interpolated > floor.len() * 3 / 4, "{interpolated} of {} floor pixels interpolated", floor.len());
    let rmse = |image: &[Vec4]| {
        let sum: f32 = floor.iter().map(|&i| ((image[i].x - truth.radiance[i].x) / truth.radiance[i].x).powi(2)).sum();
        (sum / floor.len() as f32).sqrt()
    };
    // R bilinear over the same quads (the same refinement, judging nothing but ids), from the same corners.
    let mut bilinear: Vec<Vec4> = got.radiance.iter().map(|r| if r.w == SENSED { *r } else { Vec4::ZERO }).collect();
    let mut refinement = Refinement::start(&got.gbuffer, 16, 1e30).0;
    while !refinement.is_finished() {
        refinement.step(&bilinear, &[], &[]);
    }
    interpolate_cpu(&mut bilinear, 48, refinement.interpolated());
    assert!(
        rmse(&bilinear) > 0.02,
        "bilinear R is {:.3} % off: the light does not curve enough",
        100.0 * rmse(&bilinear)
    );
    assert!(rmse(&got.radiance) < 1e-4, "exact interpolation is {:.4} % off", 100.0 * rmse(&got.radiance));
}
