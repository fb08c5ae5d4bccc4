//! CPU twins of the GPU post-passes, used to test them: the id-constrained filter and the composition.
//! (The interpolation's twin sits with the refinement that defines it: `sensors::refine::interpolate_cpu`.)

use glam::{Vec3, Vec4};

use crate::gbuffer::GBufferData;
use crate::scene::{ImageSize, NO_SURFACE, SurfaceId};

/// Gaussian of radius `radius` (σ = radius/2) over `source`, only over pixels of the centre's surface id and
/// light mask (`masks`, one per pixel, or empty for none), weights renormalised over the pixels taken (paper
/// §III-H). Background pixels and radius 0 pass through.
pub fn filter(source: &[Vec4], ids: &[SurfaceId], masks: &[u64], size: ImageSize, radius: u32) -> Vec<Vec4> {
    let mask = |i: i64| masks.get(i as usize).copied().unwrap_or(0);
    let (w, h, r) = (size.width as i64, size.height as i64, radius as i64);
    let inv_two_sigma2 = if r > 0 { 1.0 / (0.5 * (r * r) as f32) } else { 0.0 };
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let id = ids[i as usize];
            if id == NO_SURFACE || r == 0 {
                return source[i as usize];
            }
            let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
            for dy in -r..=r {
                for dx in -r..=r {
                    let (qx, qy) = (x + dx, y + dy);
                    if qx < 0 || qy < 0 || qx >= w || qy >= h {
                        continue;
                    }
                    let j = qy * w + qx;
                    if ids[j as usize] != id || mask(j) != mask(i) {
                        continue;
                    }
                    let k = (-((dx * dx + dy * dy) as f32) * inv_two_sigma2).exp();
                    sum += k * source[(qy * w + qx) as usize].truncate();
                    weight += k;
                }
            }
            (sum / weight).extend(source[i as usize].w)
        })
        .collect()
}

/// `Le + Kd·R` per pixel, alpha 1, where a surface is seen; `background`, alpha 0, where none is (the
/// alpha is the pixel's coverage).
pub fn compose(g: &GBufferData, radiance: &[Vec4], background: Vec3) -> Vec<Vec4> {
    (radiance.iter().enumerate())
        .map(|(i, r)| match g.surface[i] {
            NO_SURFACE => background.extend(0.0),
            _ => (g.emission[i].truncate() + g.albedo[i].truncate() * r.truncate()).extend(1.0),
        })
        .collect()
}
