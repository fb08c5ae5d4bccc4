//! Which surface point each texel of the atlas stands for: the triangles rasterised in their lightmap
//! coordinates. A texel whose centre a triangle covers takes that point; a texel just outside a chart (its
//! centre within [`REACH`] of it) takes the chart's nearest point, so that bilinear filtering at the chart's
//! border blends values of its own surface and never the gutter's. Points inside geometry (a floor under a
//! box, under a wall) are moved to a part of the texel's footprint that is outside, or the texel is left to
//! its neighbours: such a point sees only the inside of what covers it, and its light would leak out
//! through bilinear filtering (lightmapper.h's users fight exactly this).

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::unwrap::Unwrapped;
use crate::gbuffer::GBufferData;
use crate::scene::bvh::Bvh;
use crate::scene::{ImageSize, Mesh, NO_SURFACE, Ray, at_barycentric};

/// How far outside a chart (in texels, from the texel's centre) a texel still takes the chart's nearest
/// point: its 8 neighbours' centres are within √2 of the border, and charts lie 2 × `GUTTER` = 4 apart.
pub const REACH: f32 = 1.5;

/// What a texel stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelPoint {
    pub triangle: u32,
    /// Barycentric weights of corners 1 and 2.
    pub bary: Vec2,
    /// The light of the triangle's back side: its front faces into geometry (a wall modelled facing out
    /// of the room it closes, which the renderer shows from either side).
    pub back: bool,
}

/// Every page's texels, page after page, row by row from the top.
#[derive(Clone, Debug)]
pub struct Texels {
    pub width: u32,
    pub height: u32,
    pub pages: u32,
    pub points: Vec<Option<TexelPoint>>,
    /// How far (scene units) the inside tests' rays start off the surface: the sensors' lift.
    pub bias: f32,
    /// Texels whose own point lay inside geometry and were moved within their footprint, and those left
    /// to their neighbours (no point of their footprint outside).
    pub moved: u64,
    pub buried: u64,
    /// Texels whose triangle's front faces into geometry and whose back is open: the back's light.
    pub backs: u64,
}

/// The texel's point candidate: its distance from the texel's centre (texels; 0 inside), the triangle and
/// the barycentric weights.
type Candidate = (f32, u32, Vec2);

/// Where a texel's point was placed ([`Texels::rasterise`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Placed {
    /// Its own point (or none: outside every chart's reach).
    Own,
    /// Inside geometry: moved to the open part of its footprint.
    Moved,
    /// Inside geometry all over its footprint: left to its neighbours.
    Buried,
    /// Its front faces into geometry or out of the scene, its back into the scene: the back's light.
    Back,
}

impl Texels {
    /// Rasterises `unwrapped`'s triangles of `mesh`; `bvh` (of the whole mesh) finds points inside geometry,
    /// `bias` (scene units) lifts their test rays off the surface as the sensors are lifted.
    pub fn rasterise(mesh: &Mesh, bvh: &Bvh, unwrapped: &Unwrapped, bias: f32) -> Self {
        let (w, h, pages) = (unwrapped.width, unwrapped.height, unwrapped.pages);
        let page_texels = w as usize * h as usize;
        let mut best: Vec<Option<Candidate>> = vec![None; page_texels * pages as usize];
        let size = Vec2::new(w as f32, h as f32);
        for (t, uv) in unwrapped.uv.iter().enumerate() {
            let c = uv.map(|p| p * size);
            let (lo, hi) = (c[0].min(c[1]).min(c[2]) - REACH, c[0].max(c[1]).max(c[2]) + REACH);
            let (x0, y0) = ((lo.x.floor().max(0.0)) as u32, (lo.y.floor().max(0.0)) as u32);
            let (x1, y1) = ((hi.x.ceil() as u32).min(w), (hi.y.ceil() as u32).min(h));
            let base = unwrapped.page[t] as usize * page_texels;
            for y in y0..y1 {
                for x in x0..x1 {
                    let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let Some((d, bary)) = nearest(&c, q) else { continue };
                    let slot = &mut best[base + y as usize * w as usize + x as usize];
                    if d <= REACH && slot.is_none_or(|(best, _, _)| d < best) {
                        *slot = Some((d, t as u32, bary));
                    }
                }
            }
        }
        // Points inside geometry: their back side where it looks into the scene, else moved within the
        // texel's footprint (a 4 × 4 grid over it, nearest the centre first), else left to the neighbours.
        let mut offsets = grid(4);
        offsets.sort_by(|a, b| a.length_squared().total_cmp(&b.length_squared()));
        let placed: Vec<(Option<TexelPoint>, Placed)> = best
            .par_iter()
            .enumerate()
            .map(|(i, candidate)| {
                let Some((_, triangle, bary)) = *candidate else { return (None, Placed::Own) };
                let point = TexelPoint { triangle, bary, back: false };
                let front = look(mesh, bvh, point, bias);
                if front == Look::Scene {
                    return (Some(point), Placed::Own);
                }
                // The back is tested only where the front does not look into the scene.
                let back = TexelPoint { back: true, ..point };
                match (front, look(mesh, bvh, back, bias)) {
                    (_, Look::Scene) => return (Some(back), Placed::Back),
                    (Look::Nothing, _) => return (Some(point), Placed::Own),
                    _ => {}
                }
                let j = i % page_texels;
                let centre = Vec2::new((j % w as usize) as f32 + 0.5, (j / w as usize) as f32 + 0.5);
                let uv = unwrapped.uv[triangle as usize].map(|p| p * size);
                let moved = (offsets.iter())
                    .filter_map(|&o| barycentric_2d(&uv, centre + o).filter(|b| in_triangle(*b)))
                    .map(|bary| TexelPoint { triangle, bary, back: false })
                    .find(|p| !inside(mesh, bvh, *p, bias));
                match moved {
                    Some(p) => (Some(p), Placed::Moved),
                    None => (None, Placed::Buried),
                }
            })
            .collect();
        let count = |kind: Placed| placed.iter().filter(|(_, k)| *k == kind).count() as u64;
        let (moved, buried, backs) = (count(Placed::Moved), count(Placed::Buried), count(Placed::Back));
        let points = placed.into_iter().map(|(p, _)| p).collect();
        Texels { width: w, height: h, pages, points, bias, moved, buried, backs }
    }

    /// The texels with a point.
    pub fn count(&self) -> usize {
        self.points.iter().filter(|p| p.is_some()).count()
    }

    /// The texels' points as a G-buffer (one row, texel i at pixel i; no surface where a texel has no
    /// point): what `Renderer::sense_points` senses.
    pub fn gbuffer(&self, mesh: &Mesh) -> GBufferData {
        gbuffer(mesh, &self.points)
    }

    /// The texels whose light (`light`, per texel) differs from a neighbour's by more than [`CONTRAST`] of
    /// the brighter: a shadow's boundary, a contact shadow's edge, where one point stands badly for the
    /// texel's footprint. Neighbours: the 4 around, on the page, holding a point.
    pub fn contrasted(&self, light: &[Vec3]) -> Vec<usize> {
        let (w, h) = (self.width as usize, self.height as usize);
        let luminance = |i: usize| crate::light::groups::luminance(light[i]);
        (0..self.points.len())
            .filter(|&i| {
                let (j, base) = (i % (w * h), i - i % (w * h));
                let (x, y) = (j % w, j / w);
                let around = [(x > 0, -1i64), (x + 1 < w, 1), (y > 0, -(w as i64)), (y + 1 < h, w as i64)];
                self.points[i].is_some()
                    && around.iter().filter(|(inside, _)| *inside).any(|&(_, d)| {
                        let k = base + (j as i64 + d) as usize;
                        let (a, b) = (luminance(i), luminance(k));
                        self.points[k].is_some() && (a - b).abs() > CONTRAST * a.max(b)
                    })
            })
            .collect()
    }

    /// [`FOOTPRINT`] points spread over texel `i`'s footprint: each on the triangle that covers it among
    /// those of the texel and its 8 neighbours, else (beyond its chart's border) the nearest point of
    /// texel i's own triangle; those inside geometry left out.
    pub fn footprint(&self, i: usize, (mesh, bvh): (&Mesh, &Bvh), unwrapped: &Unwrapped) -> Vec<TexelPoint> {
        let Some(point) = self.points[i] else { return Vec::new() };
        let (w, h) = (self.width as i64, self.height as i64);
        let (j, base) = (i as i64 % (w * h), i as i64 - i as i64 % (w * h));
        let (x, y) = (j % w, j / w);
        let size = Vec2::new(w as f32, h as f32);
        let corners = |t: u32| unwrapped.uv[t as usize].map(|p| p * size);
        let mut near: Vec<u32> = (-1..=1)
            .flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
            .filter(|&(nx, ny)| (0..w).contains(&nx) && (0..h).contains(&ny))
            .filter_map(|(nx, ny)| self.points[(base + ny * w + nx) as usize].map(|p| p.triangle))
            .collect();
        near.sort_unstable();
        near.dedup();
        let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        (grid(FOOTPRINT_SIDE).into_iter())
            .filter_map(|o| {
                let q = centre + o;
                let covering = near.iter().find_map(|&t| {
                    barycentric_2d(&corners(t), q).filter(|b| in_triangle(*b)).map(|bary| TexelPoint {
                        triangle: t,
                        bary,
                        back: point.back,
                    })
                });
                covering.or_else(|| nearest(&corners(point.triangle), q).map(|(_, bary)| TexelPoint { bary, ..point }))
            })
            .filter(|p| !inside(mesh, bvh, *p, self.bias))
            .collect()
    }
}

/// Above this relative difference of light between neighbouring texels a texel is taken over its
/// footprint ([`Texels::contrasted`]).
pub const CONTRAST: f32 = 0.1;

/// Points a texel is taken over ([`Texels::footprint`]): 2 × 2, stratified.
pub const FOOTPRINT_SIDE: usize = 2;
pub const FOOTPRINT: usize = FOOTPRINT_SIDE * FOOTPRINT_SIDE;

/// `points` as a G-buffer (one row, point i at pixel i; no surface where there is none), each facing the
/// side of its triangle it stands for.
pub fn gbuffer(mesh: &Mesh, points: &[Option<TexelPoint>]) -> GBufferData {
    let n = points.len();
    let mut g = GBufferData {
        size: ImageSize { width: n as u32, height: 1 },
        position: vec![Vec4::ZERO; n],
        normal: vec![Vec4::ZERO; n],
        albedo: vec![Vec4::ZERO; n],
        emission: vec![Vec4::ZERO; n],
        surface: vec![NO_SURFACE; n],
    };
    for (i, p) in points.iter().enumerate() {
        let Some(p) = p else { continue };
        let t = p.triangle as usize;
        let position = point_of(mesh, *p);
        let tri = &mesh.triangles[t];
        let emits = mesh.material_of(tri.surface).is_emitter() && !p.back;
        let side = if p.back { -1.0 } else { 1.0 };
        g.position[i] = position.extend(1.0);
        g.normal[i] = (side * mesh.shading_normal(t, position)).extend(if p.back { 0.0 } else { 1.0 });
        g.albedo[i] = mesh.albedo_at(t, position).extend(1.0);
        g.emission[i] = if emits { mesh.emission_at(t, position) } else { Vec3::ZERO }.extend(1.0);
        g.surface[i] = tri.surface;
    }
    g
}

/// The surface point a texel stands for.
pub fn point_of(mesh: &Mesh, p: TexelPoint) -> Vec3 {
    at_barycentric(&mesh.triangles[p.triangle as usize].v, p.bary)
}

/// Directions a point's inside test casts rays along, in its tangent frame (x, y tangent, z the normal):
/// eight around the horizon, 15° up, where the walls of whatever covers the point are met; and straight up.
const INSIDE_RAYS: usize = 9;

/// What a side of a surface point looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Look {
    /// Most test rays meet a back face first: the inside of a box resting on it, of a wall across it.
    Inside,
    /// Not inside, and some ray meets the scene.
    Scene,
    /// Every ray leaves the scene (a floor under the open sky, or a wall's side facing out of the world).
    Nothing,
}

/// What the side `p` of a surface point looks at ([`Look`]), by [`INSIDE_RAYS`] test rays.
fn look(mesh: &Mesh, bvh: &Bvh, p: TexelPoint, bias: f32) -> Look {
    match hits(mesh, bvh, p, bias) {
        (backs, _) if 2 * backs > INSIDE_RAYS => Look::Inside,
        (0, 0) => Look::Nothing,
        _ => Look::Scene,
    }
}

/// Whether the point `p` lies inside geometry ([`Look::Inside`]).
fn inside(mesh: &Mesh, bvh: &Bvh, p: TexelPoint, bias: f32) -> bool {
    look(mesh, bvh, p, bias) == Look::Inside
}

/// How many of `p`'s test rays meet a back face first, and how many a front.
fn hits(mesh: &Mesh, bvh: &Bvh, p: TexelPoint, bias: f32) -> (usize, usize) {
    let t = &mesh.triangles[p.triangle as usize];
    let n = if p.back { -t.normal } else { t.normal };
    let origin = point_of(mesh, p) + n * bias;
    let (x, y) = n.any_orthonormal_pair();
    let (s, c) = 15f32.to_radians().sin_cos();
    let (mut backs, mut fronts) = (0, 0);
    for k in 0..INSIDE_RAYS {
        let dir = if k + 1 == INSIDE_RAYS {
            n
        } else {
            let a = k as f32 * std::f32::consts::TAU / (INSIDE_RAYS - 1) as f32;
            (x * a.cos() + y * a.sin()) * c + n * s
        };
        if let Some(hit) = bvh.intersect(&Ray::new(origin, dir), 0.0, f32::INFINITY) {
            match dir.dot(mesh.triangles[hit.triangle as usize].normal) > 0.0 {
                true => backs += 1,
                false => fronts += 1,
            }
        }
    }
    (backs, fronts)
}

/// The centres of an `n` × `n` grid over a texel, as offsets from its centre, in texels.
fn grid(n: usize) -> Vec<Vec2> {
    let at = |k: usize| (k as f32 + 0.5) / n as f32 - 0.5;
    (0..n * n).map(|k| Vec2::new(at(k % n), at(k / n))).collect()
}

/// The barycentric weights of corners 1 and 2 of `q` in the 2D triangle `c` (`None` if degenerate).
fn barycentric_2d(c: &[Vec2; 3], q: Vec2) -> Option<Vec2> {
    let (e1, e2, d) = (c[1] - c[0], c[2] - c[0], q - c[0]);
    let det = e1.perp_dot(e2);
    if det.abs() < 1e-12 {
        return None;
    }
    Some(Vec2::new(d.perp_dot(e2), e1.perp_dot(d)) / det)
}

fn in_triangle(b: Vec2) -> bool {
    b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0
}

/// The distance from `q` to the 2D triangle `c` (0 inside) and the barycentric weights of its nearest point;
/// `None` for a degenerate triangle.
fn nearest(c: &[Vec2; 3], q: Vec2) -> Option<(f32, Vec2)> {
    let b = barycentric_2d(c, q)?;
    if in_triangle(b) {
        return Some((0.0, b));
    }
    // Outside: the nearest point lies on an edge.
    let mut best: Option<(f32, Vec2)> = None;
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let (a, e) = (c[i], c[j] - c[i]);
        let s = ((q - a).dot(e) / e.length_squared().max(1e-20)).clamp(0.0, 1.0);
        let p = a + e * s;
        let d = p.distance(q);
        if best.is_none_or(|(bd, _)| d < bd) {
            let mut w = [0.0f32; 3];
            w[i] = 1.0 - s;
            w[j] = s;
            best = Some((d, Vec2::new(w[1], w[2])));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_inside_and_outside() {
        let c = [Vec2::ZERO, Vec2::new(4.0, 0.0), Vec2::new(0.0, 4.0)];
        let (d, b) = nearest(&c, Vec2::new(1.0, 1.0)).unwrap();
        assert_eq!(d, 0.0);
        assert!((b - Vec2::new(0.25, 0.25)).length() < 1e-6);
        // Below the edge 0–1, at x = 2: the nearest point is (2, 0), halfway along it.
        let (d, b) = nearest(&c, Vec2::new(2.0, -1.0)).unwrap();
        assert!((d - 1.0).abs() < 1e-6 && (b - Vec2::new(0.5, 0.0)).length() < 1e-6, "{d} {b}");
        assert!(nearest(&[Vec2::ZERO, Vec2::ONE, Vec2::ONE * 2.0], Vec2::ZERO).is_none());
    }
}
