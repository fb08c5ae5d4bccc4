//! Every pixel right (docs/DESIGN.md §11): the supersampling's GPU resolve against its CPU twin, what it
//! detects, and whole images against the oracle integrated over each pixel's square.

mod common;

use glam::{Vec2, Vec3, Vec4};
use sensorlight::gbuffer::cast;
use sensorlight::light::groups::Lights;
use sensorlight::params::{Antialiasing, Overrides, RenderParams};
use sensorlight::passes::resolve::{ResolvePass, ResolveTargets};
use sensorlight::reference::sampling::hash;
use sensorlight::scene::bvh::Bvh;
use sensorlight::scene::{ImageSize, NO_SURFACE, Scene};
use sensorlight::sensors::hints;
use sensorlight::sensors::refine::Visibility;
use sensorlight::supersample::{self, SAMPLES, SubSampleLight};
use sensorlight::vk::{Access, barrier, transfer};

/// The resolve on the GPU and its CPU twin agree, on the small-light scene's real G-buffer (edges of the
/// occluder, the light's rim, the shadow's edges) with arbitrary final R per pixel and visibilities.
#[test]
fn gpu_resolve_matches_the_cpu_twin() {
    let (w, h) = (40u32, 30u32);
    let scene = common::small_light((w, h));
    let size = ImageSize { width: w, height: h };
    let scale = scene.mesh.scale();
    let (bias, near) = (2e-4 * scale, 1e-3 * scale);
    let noise = |i: u32, salt: u64| hash(i as u64 ^ (salt << 40)) as f32 / u64::MAX as f32;
    let composed: Vec<Vec4> =
        (0..w * h).map(|i| Vec3::new(noise(i, 1), noise(i, 2), noise(i, 3)).extend(noise(i, 4))).collect();
    let lights = Lights::new(&scene.mesh);
    let (g, plan, samples, got) = common::gpu(|device| {
        let (gpu_scene, gbuffer, g) = common::raster_gbuffer(device, &scene, size);
        let bvh = Bvh::build(&scene.mesh.triangles);
        let points = hints::light_points(&lights);
        let bits = hints::group_bits(&lights);
        let masks = hints::hints(&bvh, &points, &g, bias, near);
        let flags = supersample::detect(&scene, &g, &masks, &bits);
        let plan = supersample::plan(&scene, &bvh, &g, &flags);
        let visibility: Vec<Visibility> =
            (0..w * h).map(|i| std::array::from_fn(|k| if k == 0 { noise(i, 7) } else { -1.0 })).collect();
        let shadow = supersample::ShadowPoints::new(&lights);
        let light = SubSampleLight {
            visibility: &visibility,
            hints: &masks,
            bvh: &bvh,
            points: &points,
            bits: &bits,
            shadow: &shadow,
            bias,
            near,
        };
        let all = 0..plan.pixels.len();
        let seen = plan.samples(&scene, &bvh, &g, all.clone());
        let mut samples = supersample::sub_samples(&g, (&plan, all.clone(), &seen), Some(light), None);
        // Every fifth sample on a surface with its own R (the radiance cache's), not its donor's.
        for (k, s) in samples.iter_mut().enumerate().filter(|(k, s)| k % 5 == 0 && s.position[3] == 1.0) {
            s.own = [noise(k as u32, 8), noise(k as u32, 9), noise(k as u32, 10), 1.0];
        }
        // A sky that differs along every ray: the GPU must take each leaving sample's own.
        supersample::carry_sky(&mut samples, &seen.points, |at| Vec3::new(0.1 + at.x.fract(), 0.2, 0.3 + at.y.fract()));
        let usage = ash::vk::BufferUsageFlags::STORAGE_BUFFER | ash::vk::BufferUsageFlags::TRANSFER_SRC;
        let composed_buffer = transfer::upload(device, "composed", &composed, usage).unwrap();
        let image = transfer::upload(device, "image", &vec![Vec4::splat(-1.0); (w * h) as usize], usage).unwrap();
        let resolved = transfer::upload(device, "resolved", &vec![Vec4::ZERO; plan.pixels.len()], usage).unwrap();
        let mut pass = ResolvePass::new(device).unwrap();
        let targets = ResolveTargets {
            composed: &composed_buffer,
            image: &image,
            resolved: &resolved,
            gbuffer: &gbuffer,
            scene: &gpu_scene,
        };
        pass.bind(device, (&plan.gpu_pixels(0..plan.pixels.len()), &samples), targets, (true, bias)).unwrap();
        device
            .submit_and_wait(|enc| {
                barrier::global(enc, &[Access::TransferWrite], &[Access::ComputeWrite]);
                pass.record(enc);
                Ok(())
            })
            .unwrap();
        let image = transfer::read_buffer::<Vec4>(device, &image, (w * h) as usize).unwrap();
        let resolved = transfer::read_buffer::<Vec4>(device, &resolved, plan.pixels.len()).unwrap();
        (g, plan, samples, (image, resolved))
    });
    let expected = supersample::resolve_cpu(
        (&plan.gpu_pixels(0..plan.pixels.len()), &samples),
        &composed,
        &g,
        (&lights, bias, true),
    );
    assert!(plan.pixels.len() > 50, "edges and shadow edges are supersampled: {}", plan.pixels.len());
    let partial = expected.iter().filter(|(image, _)| image.w > 0.0 && image.w < 1.0).count();
    assert!(partial > 10, "some pixels are partly background: {partial}");
    let (image, resolved) = got;
    for (n, (&i, (e_image, e_r))) in plan.pixels.iter().zip(&expected).enumerate() {
        let (a, b) = (image[i as usize], resolved[n]);
        let close = |a: Vec4, b: Vec4| (a - b).abs().max_element() <= 1e-4 * b.max_element().max(1.0);
        assert!(close(a, *e_image), "pixel {i}: GPU image {a}, CPU {e_image}");
        assert!(close(b, *e_r), "pixel {i}: GPU R {b}, CPU {e_r}");
    }
    let untouched = (0..(w * h) as usize).filter(|i| !plan.pixels.contains(&(*i as u32)));
    assert!(untouched.map(|i| image[i]).all(|v| v == Vec4::splat(-1.0)), "only supersampled pixels are written");
}

/// Whole images, nothing masked, against the oracle integrated over each pixel: the shipped Cornell box
/// (ε 0.1) and the small light's penumbrae at its own size with direct light alone (ε 0: where a penumbra
/// ends inside a pixel, a dim pixel, is what is hard) within 1.5 %, where pixel centres alone are several
/// times further (edges); the interior no worse than with centres against the same oracle.
#[test]
fn whole_images_within_one_and_a_half_percent_of_the_pixel_area_oracle() {
    for (file, size, epsilon, samples) in [
        ("scenes/cornell/cornell.toml", (128, 128), 0.1, 1024),
        ("scenes/small-light/small-light.toml", (320, 240), 0.0, 512),
    ] {
        let mut scene = Scene::load(&common::project(file)).unwrap();
        scene.image = ImageSize { width: size.0, height: size.1 };
        let [on, off] = common::against_the_area_oracle(&scene, epsilon, samples);
        let (own, centres) = (on.whole.own_error.unwrap(), off.whole.own_error.unwrap());
        assert!(own <= 0.015, "{file}: whole image {own:.4}");
        assert!(centres > 2.0 * own, "{file}: pixel centres alone are further: {centres:.4} against {own:.4}");
        assert!(on.interior.own_error.unwrap() <= off.interior.own_error.unwrap() + 0.002, "{file}: interior {on:?}");
    }
}

/// Thin geometry: fence bars and a light seen edge-on, each thinner than a pixel, within 3 % over the whole
/// image (the centres alone miss most of them).
#[test]
fn thin_bars_and_a_light_seen_edge_on_within_three_percent() {
    let scene = common::fence((96, 64));
    let [on, off] = common::against_the_area_oracle(&scene, 0.1, 1024);
    let own = on.whole.own_error.unwrap();
    assert!(own <= 0.03, "whole image {own:.4}");
    assert!(off.whole.own_error.unwrap() > 2.0 * own, "pixel centres alone: {:?}", off.whole);
}

/// The program's defaults with direct light only (ε = 0) and `aa`.
fn direct_defaults(aa: Antialiasing) -> common::Setup {
    let p = RenderParams::resolve(None, &Overrides { epsilon: Some(0.0), aa: Some(aa), ..Default::default() }).unwrap();
    common::Setup::of(&p)
}

/// What is supersampled: the outlines of the occluder and the light and the shadow's edges, and nothing
/// with `--aa off`, whose image is the same elsewhere.
#[test]
fn only_pixels_that_are_not_uniform_are_supersampled() {
    let (w, h) = (80i64, 60i64);
    let scene = common::small_light((w as u32, h as u32));
    let on = common::render(&scene, &direct_defaults(Antialiasing::On), None);
    let off = common::render(&scene, &direct_defaults(Antialiasing::Off), None);
    let share = on.supersampled.len() as f64 / (w * h) as f64;
    assert!(share > 0.01 && share < 0.25, "{} pixels supersampled ({:.1} %)", on.supersampled.len(), share * 100.0);
    assert_eq!(on.stats.supersampled_pixels, on.supersampled.len() as u64);
    assert!(off.supersampled.is_empty() && off.stats.supersampled_pixels == 0, "--aa off supersamples nothing");
    // Along a silhouette, one of each pair of 4-neighbours of two surfaces is supersampled, unless the edge
    // runs along their common side (the scene's edges are axis-aligned: some do).
    let ids = &off.gbuffer.surface;
    let supersampled = |i: i64| on.supersampled.binary_search(&(i as u32)).is_ok();
    let (mut pairs, mut covered) = (0, 0);
    for i in 0..w * h {
        for j in [i + 1, i + w].into_iter().filter(|&j| j < w * h && (j != i + 1 || (i + 1) % w != 0)) {
            if ids[i as usize] != ids[j as usize] {
                pairs += 1;
                covered += (supersampled(i) || supersampled(j)) as u32;
            }
        }
    }
    assert!(covered * 10 >= pairs * 9, "{covered} of {pairs} silhouette pairs supersampled");
    let differ: Vec<usize> = (0..on.image.len()).filter(|&i| on.image[i] != off.image[i]).collect();
    assert!(
        differ.iter().all(|&i| on.supersampled.binary_search(&(i as u32)).is_ok()),
        "--aa on differs from off only where it supersampled"
    );
    assert!(
        differ.len() * 2 > on.supersampled.len(),
        "and there mostly: {} of {}",
        differ.len(),
        on.supersampled.len()
    );
}

/// The samples' weights are what each surface covers of a pixel's square (`supersample::coverage`): on the
/// small light's table and box, whose lit tops and the floor border faces the light is behind, each
/// surface's weighed share of every supersampled pixel that shows two is within 1 % of a dense 128 × 128
/// grid of camera rays (measured: 0.6 %, the net's 1 024 rays on a slanted edge), where 1/64 per sample is
/// 4 % off on some (a sliver that no sample meets, or that one sample stands for at 1/64).
#[test]
fn sample_weights_are_the_share_of_the_square_each_surface_covers() {
    let size = ImageSize { width: 160, height: 120 };
    let mut scene = Scene::load(&common::project("scenes/small-light/small-light.toml")).unwrap();
    scene.image = size;
    let bvh = Bvh::build(&scene.mesh.triangles);
    let g = cast::cast(&scene, &bvh, size);
    let lights = Lights::new(&scene.mesh);
    let scale = scene.mesh.scale();
    let (points, bits) = (hints::light_points(&lights), hints::group_bits(&lights));
    let masks = hints::hints(&bvh, &points, &g, 2e-4 * scale, 1e-3 * scale);
    let plan = supersample::plan(&scene, &bvh, &g, &supersample::detect(&scene, &g, &masks, &bits));
    let samples = plan.samples(&scene, &bvh, &g, 0..plan.pixels.len());
    let (mut worst, mut worst_uniform, mut mixed) = (0.0f32, 0.0f32, 0);
    let m = 128;
    for (n, &pixel) in plan.pixels.iter().enumerate() {
        let range = n * SAMPLES..(n + 1) * SAMPLES;
        let (ids, weights) = (&samples.seen.surface[range.clone()], &samples.weights[range]);
        assert!((weights.iter().sum::<f32>() - 1.0).abs() < 1e-5, "pixel {pixel}: weights {weights:?}");
        let corner = Vec2::new((pixel % size.width) as f32, (pixel / size.width) as f32);
        let mut dense: Vec<(u32, f32)> = Vec::new();
        for i in 0..m * m {
            let at = corner + Vec2::new((i % m) as f32 + 0.5, (i / m) as f32 + 0.5) / m as f32;
            let ray = scene.camera.ray(at.x, at.y, size.width, size.height);
            let id = cast::first_surface(&scene, &bvh, &ray).map_or(NO_SURFACE, |v| v.surface);
            match dense.iter_mut().find(|(k, _)| *k == id) {
                Some((_, share)) => *share += 1.0 / (m * m) as f32,
                None => dense.push((id, 1.0 / (m * m) as f32)),
            }
        }
        if dense.len() < 2 {
            continue;
        }
        mixed += 1;
        for (id, share) in dense {
            let weighed: f32 = ids.iter().zip(weights).filter(|(k, _)| **k == id).map(|(_, w)| w).sum();
            let uniform = ids.iter().filter(|k| **k == id).count() as f32 / SAMPLES as f32;
            worst = worst.max((weighed - share).abs());
            worst_uniform = worst_uniform.max((uniform - share).abs());
        }
    }
    assert!(mixed > 100, "pixels showing two surfaces: {mixed}");
    assert!(worst <= 0.01, "a surface's weighed share {worst:.4} from the dense grid's");
    assert!(worst_uniform > 0.03, "1/64 per sample: {worst_uniform:.4} (the test could tell them apart)");
}

/// Two rooms behind a wall with a vertical slit a fifth of a pixel wide; the camera's room lit dimly, the
/// other brightly by a panel on its far wall, which is what the slit shows, lit only by the room's other
/// walls (it holds the panel, so no direct light). No pixel centre sees through the slit, so a sample there
/// has no pixel of its surface around it: its R comes from the radiance cache, where a pixel of the wall
/// around the slit lent it its own light, a tenth as bright. Against the oracle over each pixel's square:
/// the slit's column (its pixels' sum) and the whole image.
#[test]
fn a_room_seen_through_a_slit_takes_its_light_from_the_radiance_cache() {
    use sensorlight::reference::integrator::Integrator;
    use sensorlight::scene::builtin::rect;
    use sensorlight::scene::camera::Camera;
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let (c, slit) = (y, 0.01);
    let half = (1.0 - slit / 2.0) / 2.0;
    // The two rooms' shell (`common::two_rooms`), its dividing wall at x = 0 cut by the slit.
    let mut groups = common::two_rooms_shell();
    groups.extend([
        ("wall", 0, [rect(c + z * (1.0 - half), z * half, y, x), rect(c - z * (1.0 - half), z * half, y, x)].concat()),
        ("dim", 1, rect(Vec3::new(-1.0, 1.99, 0.0), x * 0.3, z * 0.3, -y)),
        ("bright", 2, rect(Vec3::new(1.99, 1.0, 0.6), z * 0.2, y * 0.2, -x)),
    ]);
    let materials = vec![
        common::material("white", 0.8, 0.0),
        common::material("dim", 0.8, 2.0),
        common::material("bright", 0.8, 200.0),
    ];
    let camera = Camera::look_at(Vec3::new(-1.8, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), y, 50.0).unwrap();
    let scene = common::scene(groups, materials, camera, (48, 32));
    let p = RenderParams::resolve(None, &Overrides::default()).unwrap();
    let out = common::render(&scene, &common::Setup::of(&p), None);
    let oracle = Integrator::new(&scene, p.estimator, 1024, 7).unwrap().render(scene.image, Antialiasing::On, &|_| ());
    let luminance = |v: Vec4| v.truncate().dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let column = (scene.camera.project(Vec3::ZERO, 48, 32).unwrap().x) as usize;
    let (mut render, mut truth) = (0.0, 0.0);
    for row in 4..28 {
        let i = row * 48 + column;
        eprintln!("{row}: render {:.4} oracle {:.4}", luminance(out.image[i]), luminance(oracle.image[i]));
        render += luminance(out.image[i]);
        truth += luminance(oracle.image[i]);
    }
    eprintln!("column {column}: render {render:.4} oracle {truth:.4}");
    assert!((render / truth - 1.0).abs() < 0.05, "the slit's column: render {render:.4}, oracle {truth:.4}");
}

/// The door ajar's light under the door, a streak on the floor of the camera's room narrower than a pixel at
/// 80 × 60 that falls between the pixel centres (none of their hints sees the light): the corners of the
/// pixels' squares see it (`supersample::light_between_centres`), so those pixels are supersampled. Direct
/// light with the program's defaults, against the oracle over each pixel's square: the streak's pixels
/// summed, where with the centres' hints alone they were black.
#[test]
fn a_streak_of_light_between_the_pixel_centres_is_supersampled() {
    use sensorlight::params::Bounces;
    use sensorlight::reference::integrator::Integrator;
    let mut scene = Scene::load(&common::project("scenes/door-ajar/door-ajar.toml")).unwrap();
    scene.image = ImageSize { width: 80, height: 60 };
    let flags = Overrides { bounces: Some(Bounces::Fixed(0)), ..Default::default() };
    let p = RenderParams::resolve(None, &flags).unwrap();
    let out = common::render(&scene, &common::Setup::of(&p), None);
    let oracle = Integrator::new(&scene, p.estimator, 1024, 7).unwrap().render(scene.image, Antialiasing::On, &|_| ());
    let luminance = |v: Vec4| v.truncate().dot(Vec3::new(0.2126, 0.7152, 0.0722)) as f64;
    // The floor in front of the door's foot (scripts/make_hard_scenes.py; the camera of the scene file).
    let streak: Vec<usize> = (33..36).flat_map(|y| (30..40).map(move |x| y * 80 + x)).collect();
    let (render, truth): (f64, f64) =
        streak.iter().fold((0.0, 0.0), |(r, t), &i| (r + luminance(out.image[i]), t + luminance(oracle.image[i])));
    for &i in &streak {
        eprintln!(
            "{} {}: render {:.4} oracle {:.4}",
            i % 80,
            i / 80,
            luminance(out.image[i]),
            luminance(oracle.image[i])
        );
    }
    eprintln!("the streak: render {render:.4}, oracle {truth:.4}");
    assert!(truth > 0.2, "the oracle sees the streak: {truth}");
    assert!((render / truth - 1.0).abs() < 0.1, "the streak: render {render:.4}, oracle {truth:.4}");
}
