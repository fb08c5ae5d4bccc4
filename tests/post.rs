//! The GPU post-passes read back against their CPU twins: the id-constrained filter and the composition.

mod common;

use ash::vk;
use glam::{Vec3, Vec4};
use sensorlight::passes::filter::FilterPass;
use sensorlight::reference::post;
use sensorlight::reference::sampling::hash;
use sensorlight::scene::ImageSize;
use sensorlight::sensors::SensorKind;
use sensorlight::vk::{Access, Image, ImageDesc, barrier, transfer};

/// Runs the GPU filter over `source` with surface ids `ids` and light masks `masks` (empty: none).
fn gpu_filter(source: &[Vec4], ids: &[u32], masks: &[u64], size: ImageSize, radius: u32) -> Vec<Vec4> {
    common::gpu(|device| {
        let masks = if masks.is_empty() { vec![0u64; source.len()] } else { masks.to_vec() };
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let src = transfer::upload(device, "source", source, usage).unwrap();
        let dst = transfer::upload(device, "target", &vec![Vec4::splat(-1.0); source.len()], usage).unwrap();
        let desc = ImageDesc {
            format: vk::Format::R32_UINT,
            width: size.width,
            height: size.height,
            layers: 1,
            usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST,
            view_type: vk::ImageViewType::TYPE_2D,
        };
        let id_image = Image::new(device, "ids", desc).unwrap();
        transfer::write_image(device, &id_image, ids).unwrap();
        let masks = transfer::upload(device, "light masks", &masks, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
        let pass = FilterPass::new(device).unwrap();
        pass.bind(device, 0, (&src, &dst), &id_image, &masks);
        device
            .submit_and_wait(|enc| {
                barrier::global(enc, &[Access::TransferWrite], &[Access::ComputeRead]);
                pass.record(enc, 0, size, radius);
                Ok(())
            })
            .unwrap();
        transfer::read_buffer(device, &dst, source.len()).unwrap()
    })
}

fn noise(i: u32, salt: u64) -> Vec4 {
    let k = hash(i as u64 ^ salt);
    Vec4::new((k & 0xffff) as f32, ((k >> 16) & 0xffff) as f32, ((k >> 32) & 0xffff) as f32, 65535.0) / 65535.0
}

#[test]
fn gpu_filter_matches_the_cpu_twin() {
    let size = ImageSize { width: 37, height: 23 };
    let ids: Vec<u32> =
        (0..37 * 23).map(|i| if i % 37 == 0 { 0 } else { 1 + (i % 37 > (i / 37) + 5) as u32 }).collect();
    let source: Vec<Vec4> = (0..37 * 23).map(|i| noise(i, 1)).collect();
    // Light masks in bands across the surfaces (a shadow's edges), some with high bits set.
    let masks: Vec<u64> = (0..37 * 23u64).map(|i| if (i % 37) / 9 % 2 == 0 { 0b101 } else { 1 << 40 | 3 }).collect();
    for (radius, masks) in [(1, &[][..]), (3, &[][..]), (3, &masks[..])] {
        let expected = post::filter(&source, &ids, masks, size, radius);
        let got = gpu_filter(&source, &ids, masks, size, radius);
        for (i, (a, b)) in got.iter().zip(&expected).enumerate() {
            assert!((*a - *b).abs().max_element() < 2e-6, "radius {radius}, pixel {i}: GPU {a}, CPU {b}");
        }
        assert!(got != source, "radius {radius} changes the image");
    }
}

#[test]
fn filter_keeps_a_sharp_id_edge_exact_and_radius_zero_is_identity() {
    let size = ImageSize { width: 30, height: 12 };
    let ids: Vec<u32> = (0..30 * 12).map(|i| if i % 30 < 13 { 4 } else { 9 }).collect();
    let source: Vec<Vec4> = ids
        .iter()
        .map(|&id| if id == 4 { Vec4::new(1.0, 2.0, 3.0, 1.0) } else { Vec4::new(0.0, 0.5, 0.0, 1.0) })
        .collect();
    // Mixing across the edge would move a pixel by O(1); renormalising identical values rounds at 1e-7.
    for (i, (got, want)) in gpu_filter(&source, &ids, &[], size, 4).iter().zip(&source).enumerate() {
        assert!(
            (*got - *want).abs().max_element() <= 1e-6 * want.max_element(),
            "pixel {i}: {got} on a surface of {want}"
        );
    }
    let textured: Vec<Vec4> = (0..30 * 12).map(|i| noise(i, 7)).collect();
    let same = gpu_filter(&textured, &ids, &[], size, 0).iter().zip(&textured).all(|(a, b)| a == b);
    assert!(same, "radius 0 is the identity");
}

/// A shadow's edge inside one surface: lit pixels see the light points, shadowed ones do not. With the
/// light masks the filter keeps the edge sharp; without, light bleeds into the shadow.
#[test]
fn filter_keeps_a_shadow_edge_inside_one_surface_sharp() {
    let size = ImageSize { width: 30, height: 12 };
    let ids = vec![5u32; 30 * 12];
    let lit = |i: u32| i % 30 >= 15;
    let source: Vec<Vec4> =
        (0..30 * 12).map(|i| if lit(i) { Vec4::new(2.0, 2.0, 2.0, 1.0) } else { Vec4::W }).collect();
    let masks: Vec<u64> = (0..30 * 12).map(|i| if lit(i) { 0xffff } else { 0 }).collect();
    let kept = gpu_filter(&source, &ids, &masks, size, 3);
    assert!(kept.iter().zip(&source).all(|(a, b)| (*a - *b).abs().max_element() <= 1e-6 * b.max_element().max(1.0)));
    let bled = gpu_filter(&source, &ids, &[], size, 3);
    assert!(bled[14].x > 0.1, "without masks the shadow's last pixel takes light: {}", bled[14].x);
}

#[test]
fn gpu_composition_matches_the_cpu_twin() {
    let scene = common::lightbox((24, 24));
    let mut params = common::every_pixel(SensorKind::Hemicube, 8, 0.1);
    params.frame.filter_radius = 1;
    let out = common::render(&scene, &params, None);
    let expected = post::compose(&out.gbuffer, &out.radiance, params.frame.background);
    assert!(expected.iter().any(|p| p.truncate() != Vec3::ZERO));
    for (i, (a, b)) in out.image.iter().zip(&expected).enumerate() {
        assert!((*a - *b).abs().max_element() <= 1e-5 * b.max_element().max(1.0), "pixel {i}: GPU {a}, CPU {b}");
    }
}

/// With global illumination the indirect part is filtered apart: the image is still `Le + Kd·R` of the R
/// written beside it; the filter changes R only by the indirect light's smoothing (a few per cent on average
/// on the 24² lightbox, where a radius of 3 spans a quarter of a wall), and where its radius is R's own it is
/// not applied at all (bit for bit as without it).
#[test]
fn the_indirect_part_is_filtered_apart() {
    let scene = common::lightbox((24, 24));
    let render = |indirect_radius: u32| {
        let mut setup = common::every_pixel(SensorKind::Hemicube, 8, 0.0);
        setup.frame.indirect = sensorlight::params::Indirect::Bounces(sensorlight::params::Bounces::Fixed(2));
        setup.frame.indirect_filter_radius = indirect_radius;
        setup.cache = Some(sensorlight::renderer::CacheConfig::new(8, 8));
        common::render(&scene, &setup, None)
    };
    let (plain, filtered) = (render(0), render(3));
    let expected = post::compose(&filtered.gbuffer, &filtered.radiance, Vec3::ZERO);
    for (i, (a, b)) in filtered.image.iter().zip(&expected).enumerate() {
        assert!((*a - *b).abs().max_element() <= 1e-5 * b.max_element().max(1.0), "pixel {i}: GPU {a}, CPU {b}");
    }
    let moved: Vec<f32> = (plain.radiance.iter().zip(&filtered.radiance))
        .filter(|(p, _)| p.truncate().max_element() > 0.0)
        .map(|(p, f)| (f.truncate() - p.truncate()).length() / p.truncate().length())
        .collect();
    let mean = moved.iter().sum::<f32>() / moved.len() as f32;
    assert!(moved.iter().any(|&m| m > 1e-4) && mean < 0.05, "the indirect filter moves R a little: {mean} on average");
    assert_eq!(render(0).radiance, plain.radiance, "radius 0 is R's own (0): the same bits");
}

/// Pixels where no surface is seen show the background, alpha 0; surfaces keep `Le + Kd·R`, alpha 1; the GPU
/// and its CPU twin agree on both.
#[test]
fn the_background_is_composed_where_no_surface_is_seen() {
    let scene = common::small_light((32, 24));
    let background = Vec3::new(0.25, 0.5, 1.0);
    let mut params = common::every_pixel(SensorKind::Hemicube, 8, 0.1);
    params.estimator.background = background;
    params.frame.background = background;
    let out = common::render(&scene, &params, None);
    let expected = post::compose(&out.gbuffer, &out.radiance, background);
    let sky = out.gbuffer.surface.iter().filter(|&&id| id == sensorlight::scene::NO_SURFACE).count();
    assert!(sky > 0 && sky < out.image.len(), "the view holds background and surface: {sky} background pixels");
    for (i, (a, b)) in out.image.iter().zip(&expected).enumerate() {
        assert!((*a - *b).abs().max_element() <= 1e-5 * b.max_element().max(1.0), "pixel {i}: GPU {a}, CPU {b}");
        match out.gbuffer.surface[i] {
            sensorlight::scene::NO_SURFACE => assert_eq!(*a, background.extend(0.0), "pixel {i}"),
            _ => assert_eq!(a.w, 1.0, "pixel {i}"),
        }
    }
}
