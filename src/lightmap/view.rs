//! The baked scene as an engine shows it: through each pixel centre, the first surface's emission (the
//! front of an emitter) plus its albedo times the lightmap, read bilinearly at the point's lightmap
//! coordinates. `render`'s image of the same camera is what it is checked against (`tests/bake.rs`), and
//! three.js's screenshot is checked against it.

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::Atlas;
use super::unwrap::Unwrapped;
use crate::scene::bvh::Bvh;
use crate::scene::{ImageSize, Scene, interpolate};

/// One pixel of the view: the colour (alpha 1 on a surface, 0 on the background) and whether the pixel
/// shows the front of a baked surface (the lightmap holds the fronts' light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shown {
    pub colour: Vec4,
    pub front: bool,
}

/// The view of `scene` from its camera at `size`, the lightmap `atlas` laid by `unwrapped`; `background`
/// where a ray leaves the scene.
pub fn view(
    scene: &Scene,
    bvh: &Bvh,
    (unwrapped, atlas): (&Unwrapped, &Atlas),
    size: ImageSize,
    background: Vec3,
) -> Vec<Shown> {
    let mesh = &scene.mesh;
    let local = unwrapped.uv.len();
    let w = size.width as usize;
    (0..w * size.height as usize)
        .into_par_iter()
        .map(|i| {
            let ray = scene.camera.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5, size.width, size.height);
            let Some(hit) = bvh.intersect(&ray, 0.0, f32::INFINITY) else {
                return Shown { colour: background.extend(0.0), front: false };
            };
            let t = hit.triangle as usize;
            let tri = &mesh.triangles[t];
            let p = ray.at(hit.t);
            let front = ray.dir.dot(tri.normal) < 0.0;
            let emission =
                if front && mesh.material_of(tri.surface).is_emitter() { mesh.emission_at(t, p) } else { Vec3::ZERO };
            if t >= local {
                // The sun's disc: no lightmap, its emission alone.
                return Shown { colour: emission.extend(1.0), front: false };
            }
            let uv = interpolate(&tri.v, &unwrapped.uv[t], p);
            let light = atlas.bilinear(unwrapped.page[t], uv);
            Shown { colour: (emission + mesh.albedo_at(t, p) * light).extend(1.0), front }
        })
        .collect()
}
