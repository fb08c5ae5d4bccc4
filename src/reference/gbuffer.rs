//! The G-buffer by ray casting through the same pixel centres the rasteriser samples: the CPU twin of
//! `passes::gbuffer`, used to test it and as the reference integrator's visible points.

use glam::Vec4;
use rayon::prelude::*;

use crate::gbuffer::GBufferData;
use crate::scene::bvh::Bvh;
use crate::scene::{ImageSize, NO_SURFACE, Scene};

pub fn cast(scene: &Scene, bvh: &Bvh, size: ImageSize) -> GBufferData {
    let (w, h) = (size.width as usize, size.height as usize);
    let pixels: Vec<(Vec4, Vec4, Vec4, Vec4, u32)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let ray = scene.camera.ray(x, y, size.width, size.height);
            let Some(hit) = bvh.intersect(&ray, 0.0, f32::INFINITY) else {
                return (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO, Vec4::ZERO, NO_SURFACE);
            };
            let tri = &scene.mesh.triangles[hit.triangle as usize];
            let material = scene.mesh.material_of(tri.surface);
            let front = ray.dir.dot(tri.normal) < 0.0;
            let normal = if front { tri.normal } else { -tri.normal };
            let emission = if front && material.is_emitter() { material.ke } else { glam::Vec3::ZERO };
            (
                ray.at(hit.t).extend(1.0),
                normal.extend(if front { 1.0 } else { 0.0 }),
                material.kd.extend(1.0),
                emission.extend(1.0),
                tri.surface,
            )
        })
        .collect();
    let mut g = GBufferData {
        size,
        position: Vec::with_capacity(w * h),
        normal: Vec::with_capacity(w * h),
        albedo: Vec::with_capacity(w * h),
        emission: Vec::with_capacity(w * h),
        surface: Vec::with_capacity(w * h),
    };
    for (p, n, a, e, s) in pixels {
        g.position.push(p);
        g.normal.push(n);
        g.albedo.push(a);
        g.emission.push(e);
        g.surface.push(s);
    }
    g
}
