//! The G-buffer by ray casting through the same pixel centres the rasteriser samples: the CPU twin of
//! `passes::gbuffer`, used to test it and as the reference integrator's visible points; and at any points of
//! the image (the supersampling's sub-pixel samples, the oracle's samples of a pixel's square).

use glam::{Vec2, Vec4};
use rayon::prelude::*;

use crate::gbuffer::GBufferData;
use crate::scene::bvh::Bvh;
use crate::scene::{ImageSize, NO_SURFACE, Ray, Scene};

/// What a camera ray sees first: the G-buffer's values for one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Visible {
    /// xyz; w = 1.
    pub position: Vec4,
    /// Turned towards the camera; w = 1 where the front side is seen.
    pub normal: Vec4,
    pub albedo: Vec4,
    /// `Ke` (times its emission texture there) where an emitter's front is seen, else 0.
    pub emission: Vec4,
    pub surface: u32,
}

/// The surface `ray` (from the camera) sees first, if any.
pub fn first_surface(scene: &Scene, bvh: &Bvh, ray: &Ray) -> Option<Visible> {
    let hit = bvh.intersect(ray, 0.0, f32::INFINITY)?;
    let tri = &scene.mesh.triangles[hit.triangle as usize];
    let material = scene.mesh.material_of(tri.surface);
    let front = ray.dir.dot(tri.normal) < 0.0;
    let position = ray.at(hit.t);
    let shading = scene.mesh.shading_normal(hit.triangle as usize, position);
    let normal = if front { shading } else { -shading };
    let emitting = front && material.is_emitter();
    let emission = if emitting { scene.mesh.emission_at(hit.triangle as usize, position) } else { glam::Vec3::ZERO };
    Some(Visible {
        position: position.extend(1.0),
        normal: normal.extend(if front { 1.0 } else { 0.0 }),
        albedo: scene.mesh.albedo_at(hit.triangle as usize, position).extend(1.0),
        emission: emission.extend(1.0),
        surface: tri.surface,
    })
}

/// The G-buffer at the camera's points `at` (continuous pixel coordinates, see `Camera::ray`) of an image of
/// `size`, in their order; `size` of the result is `at.len()` × 1.
pub fn cast_points(scene: &Scene, bvh: &Bvh, size: ImageSize, at: &[Vec2]) -> GBufferData {
    let visible: Vec<Option<Visible>> = at
        .par_iter()
        .map(|p| first_surface(scene, bvh, &scene.camera.ray(p.x, p.y, size.width, size.height)))
        .collect();
    let n = visible.len();
    let mut g = GBufferData {
        size: ImageSize { width: n as u32, height: 1 },
        position: Vec::with_capacity(n),
        normal: Vec::with_capacity(n),
        albedo: Vec::with_capacity(n),
        emission: Vec::with_capacity(n),
        surface: Vec::with_capacity(n),
    };
    for v in visible {
        let v = v.unwrap_or(Visible {
            position: Vec4::ZERO,
            normal: Vec4::ZERO,
            albedo: Vec4::ZERO,
            emission: Vec4::ZERO,
            surface: NO_SURFACE,
        });
        g.position.push(v.position);
        g.normal.push(v.normal);
        g.albedo.push(v.albedo);
        g.emission.push(v.emission);
        g.surface.push(v.surface);
    }
    g
}

/// The G-buffer through every pixel centre.
pub fn cast(scene: &Scene, bvh: &Bvh, size: ImageSize) -> GBufferData {
    let w = size.width as usize;
    let centres: Vec<Vec2> =
        (0..w * size.height as usize).map(|i| Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5)).collect();
    GBufferData { size, ..cast_points(scene, bvh, size, &centres) }
}
