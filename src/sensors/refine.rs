//! Sensor placement and adaptive refinement (paper §III-G, docs/DESIGN.md §3 step 2).
//!
//! Sensors first go on a grid of step `dt` (plus the last row and column, so every pixel lies in a quad).
//! Each quad of four sensed corners is then either interpolated, or split at its midpoints, whose new
//! corners are sensed in the next round; quads of one pixel's width are done (all their pixels are corners):
//!
//! ```text
//!   x0        xm        x1         a quad is interpolated when its corners and every pixel in it share
//!   o---------+---------o  y0      one surface id and the same light hints (`sensors::hints`: which
//!   |         |         |          points on the lights they see), the corner normals agree, and the
//!   +---------+---------+  ym      relative variation between the corners of R, and of each light group's
//!   |         |         |          visibility, is below dradiance; otherwise the points + are sensed and
//!   o---------+---------o  y1      the four children are judged in the next round.
//!                                  o: sensed corners
//! ```
//!
//! Ownership: a quad fills `[x0, x1) × [y0, y1)`, and also its right column / bottom row where that is the
//! image's last one. Leaf quads therefore tile the image exactly and the fill is order-independent.

use glam::{Vec3, Vec4};

use crate::gbuffer::GBufferData;
use crate::gpu_types::{GpuQuad, MAX_GROUPS};
use crate::light::groups::Lights;
use crate::scene::{NO_SURFACE, SurfaceId};

/// Corner normals agree when every pair is within this angle.
pub const NORMAL_TOLERANCE_DEG: f32 = 10.0;

/// Corners see a light group alike when their visibilities of it differ by at most this.
pub const SAME_VISIBILITY: f32 = 1e-3;

/// Where only R's rest is judged (see [`Refinement::step`]), it may vary between corners by this share of
/// `dradiance`: the light left to interpolate there is the indirect light, which curves most where it
/// matters (contact shadows, corners), and the sensors the exact light no longer needs are better spent on
/// it. Measured on the Cornell box at 256² against the path tracer: share 1, 1.10 % in 13.4k sensors; 0.5,
/// 0.43 % in 16.8k; 0.25, 0.17 % in 27.4k (McGuire's box at 128²: 2.51, 1.49, 0.00 %).
pub const REST_SHARE: f32 = 0.5;

/// The relative variation of R is measured against at least this fraction of the brightest R sensed on
/// the first grid, so that black regions are not refined to the pixel on noise.
pub const DARK_FLOOR: f32 = 1e-3;

/// A rectangle of an image's pixels, `x0..x1` × `y0..y1` (ends excluded): the part of a render that must
/// be right, a tile of a render split over processes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Region {
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// Whether the closed rectangle `x0..=x1` × `y0..=y1` (a refinement quad's corners) meets it.
    pub fn meets(&self, (x0, y0): (u32, u32), (x1, y1): (u32, u32)) -> bool {
        x1 >= self.x0 && x0 < self.x1 && y1 >= self.y0 && y0 < self.y1
    }

    /// Grown by `by` pixels on every side, within an image of `width` × `height`.
    pub fn grown(self, by: u32, (width, height): (u32, u32)) -> Self {
        Self {
            x0: self.x0.saturating_sub(by),
            y0: self.y0.saturating_sub(by),
            x1: (self.x1 + by).min(width),
            y1: (self.y1 + by).min(height),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Quad {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// What a sensor saw of each light group: its visibility in [0, 1], or −1 where the group sends it nothing
/// (the exact estimator's `GpuSensorResult::visibility`).
pub type Visibility = [f32; MAX_GROUPS];

/// The refinement state between rounds of sensing.
pub struct Refinement {
    width: u32,
    height: u32,
    dradiance: f32,
    surface: Vec<SurfaceId>,
    /// Which light points each pixel sees (`sensors::hints`); empty when not given.
    hints: Vec<u64>,
    normal: Vec<Vec3>,
    /// Pixels sensed or queued for sensing.
    sensed: Vec<bool>,
    active: Vec<Quad>,
    interpolated: Vec<GpuQuad>,
    floor: Option<f32>,
    /// Where the quads are refined ([`Refinement::within`]); elsewhere they are left after the first grid.
    region: Option<Region>,
}

impl Refinement {
    /// Starts a refinement over the G-buffer `g` with grid step `tile` (a power of two); returns it with the
    /// first sensors to place: every grid pixel that shows a surface, row-major.
    pub fn start(g: &GBufferData, tile: u32, dradiance: f32) -> (Self, Vec<u32>) {
        let (w, h) = (g.size.width, g.size.height);
        let grid = |n: u32| -> Vec<u32> {
            let mut v: Vec<u32> = (0..n).step_by(tile as usize).collect();
            if *v.last().unwrap() != n - 1 {
                v.push(n - 1);
            }
            v
        };
        let (xs, ys) = (grid(w), grid(h));
        let mut active = Vec::new();
        for y in ys.windows(2).map(|p| (p[0], p[1])).chain((ys.len() == 1).then_some((0, 0))) {
            for x in xs.windows(2).map(|p| (p[0], p[1])).chain((xs.len() == 1).then_some((0, 0))) {
                active.push(Quad { x0: x.0, y0: y.0, x1: x.1, y1: y.1 });
            }
        }
        let mut r = Self {
            width: w,
            height: h,
            dradiance,
            surface: g.surface.clone(),
            hints: Vec::new(),
            normal: g.normal.iter().map(|n| n.truncate()).collect(),
            sensed: vec![false; (w * h) as usize],
            active,
            interpolated: Vec::new(),
            floor: None,
            region: None,
        };
        let mut first = Vec::new();
        for &y in &ys {
            for &x in &xs {
                r.queue(x, y, &mut first);
            }
        }
        (r, first)
    }

    /// Also keeps apart pixels that see different points on the lights (`hints`, one mask per pixel of the
    /// G-buffer): light narrower than a quad is not interpolated away.
    pub fn with_hints(mut self, hints: Vec<u64>) -> Self {
        debug_assert!(hints.len() == self.surface.len() || hints.is_empty());
        self.hints = hints;
        self
    }

    /// Refines only the quads that meet `region` (a tile and its margin): the others are neither split nor
    /// interpolated after the first grid, which is sensed everywhere so that the dark floor, and with it
    /// every decision inside the region, is the whole image's.
    pub fn within(mut self, region: Option<Region>) -> Self {
        self.region = region;
        self
    }

    fn index(&self, x: u32, y: u32) -> usize {
        (y * self.width + x) as usize
    }

    /// Queues pixel (x, y) for sensing if it shows a surface and is not sensed yet.
    fn queue(&mut self, x: u32, y: u32, out: &mut Vec<u32>) {
        let i = self.index(x, y);
        if !self.sensed[i] && self.surface[i] != NO_SURFACE {
            self.sensed[i] = true;
            out.push(i as u32);
        }
    }

    /// Judges every active quad with the radiance map `r` (all queued sensors done) and, with the exact
    /// estimator, what each sensor saw of each light group (`visibility`, per pixel, else empty); returns the
    /// next sensors to place, empty when the refinement is finished.
    ///
    /// `rest`, per pixel (else empty): R's part besides the light groups' exact light, given where the
    /// interpolation computes that light per pixel (`glsl/interpolate_exact.comp`). Then a quad whose corners
    /// see every group through the same share is judged by what is interpolated there, the rest (against R,
    /// as R's own variation is), not by R, whose curvature under a light the interpolation reproduces.
    pub fn step(&mut self, r: &[Vec4], visibility: &[Visibility], rest: &[Vec4]) -> Vec<u32> {
        let floor = *self.floor.get_or_insert_with(|| {
            let brightest = self
                .sensed
                .iter()
                .zip(r)
                .filter(|(s, _)| **s)
                .map(|(_, v)| v.truncate().max_element())
                .fold(0.0, f32::max);
            DARK_FLOOR * brightest
        });
        let mut next_quads = Vec::new();
        let mut next_sensors = Vec::new();
        for q in std::mem::take(&mut self.active) {
            if self.region.is_some_and(|r| !r.meets((q.x0, q.y0), (q.x1, q.y1))) {
                continue;
            }
            if self.can_interpolate(q, (r, rest), visibility, floor) {
                self.interpolated.push(self.owned(q));
                continue;
            }
            if q.x1 - q.x0 <= 1 && q.y1 - q.y0 <= 1 {
                continue; // every pixel is a corner: sensed
            }
            let xs = split(q.x0, q.x1);
            let ys = split(q.y0, q.y1);
            for y in ys.windows(2) {
                for x in xs.windows(2) {
                    next_quads.push(Quad { x0: x[0], y0: y[0], x1: x[1], y1: y[1] });
                }
            }
            for &y in &ys {
                for &x in &xs {
                    self.queue(x, y, &mut next_sensors);
                }
            }
        }
        self.active = next_quads;
        next_sensors
    }

    fn can_interpolate(&self, q: Quad, (r, rest): (&[Vec4], &[Vec4]), visibility: &[Visibility], floor: f32) -> bool {
        let corners = [self.index(q.x0, q.y0), self.index(q.x1, q.y0), self.index(q.x0, q.y1), self.index(q.x1, q.y1)];
        let id = self.surface[corners[0]];
        if id == NO_SURFACE || corners.iter().any(|&c| self.surface[c] != id) {
            return false;
        }
        let cos_tolerance = NORMAL_TOLERANCE_DEG.to_radians().cos();
        for a in 0..4 {
            for b in a + 1..4 {
                if self.normal[corners[a]].dot(self.normal[corners[b]]) < cos_tolerance {
                    return false;
                }
            }
        }
        let extremes = |values: &[Vec4]| {
            let (lo, hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            corners.iter().fold((lo, hi), |(lo, hi), &c| (lo.min(values[c].truncate()), hi.max(values[c].truncate())))
        };
        // The light groups' light is computed per pixel (`rest` given) and every corner sees each group
        // through the same share of it: only the rest is interpolated, so only it is judged. Where a
        // visibility varies (a penumbra), so does R's error from interpolating it, and R is judged.
        let same_light = |g: usize| {
            let seen = corners.map(|c| visibility[c][g]);
            seen.iter().all(|v| (v - seen[0]).abs() <= SAME_VISIBILITY)
        };
        let exact_light = !rest.is_empty() && !visibility.is_empty() && (0..MAX_GROUPS).all(same_light);
        let (lo, hi) = extremes(r);
        let (lo_judged, hi_judged) = if exact_light { extremes(rest) } else { (lo, hi) };
        let variation = (hi_judged - lo_judged).max_element() / hi.max_element().max(floor).max(f32::MIN_POSITIVE);
        let share = if exact_light { REST_SHARE } else { 1.0 };
        if variation >= self.dradiance * share {
            return false;
        }
        // Light a corner sees and another does not, or sees through a different share of it: a shadow's edge
        // may lie between them even where R alone varies little (a small light among brighter ones).
        let differs = |g: usize| {
            let seen = corners.map(|c| visibility[c][g]);
            let (lo, hi) = seen.iter().fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
            // Unseen (−1) counts as 0: a group some corners see and others do not.
            hi >= 0.0 && hi - lo.max(0.0) >= self.dradiance
        };
        if !visibility.is_empty() && (0..MAX_GROUPS).any(differs) {
            return false;
        }
        let hint = self.hints.get(corners[0]).copied();
        (q.y0..=q.y1).all(|y| {
            (q.x0..=q.x1).all(|x| {
                let i = self.index(x, y);
                self.surface[i] == id && self.hints.get(i).copied() == hint
            })
        })
    }

    /// The quad with its share of the image: its right column and bottom row belong to the next quad,
    /// except on the image's last column and row.
    fn owned(&self, q: Quad) -> GpuQuad {
        let own_x1 = if q.x1 == self.width - 1 { q.x1 } else { q.x1 - 1 };
        let own_y1 = if q.y1 == self.height - 1 { q.y1 } else { q.y1 - 1 };
        GpuQuad { x0: q.x0, y0: q.y0, x1: q.x1, y1: q.y1, own_x1, own_y1, _pad: [0; 2] }
    }

    /// Quads to fill by interpolation, final once [`Refinement::step`] returned no sensors.
    pub fn interpolated(&self) -> &[GpuQuad] {
        &self.interpolated
    }

    /// Pixels not final yet: those the quads still to be judged own. It only falls, round by round (children
    /// own exactly their parent's pixels), and is 0 once finished: an honest measure of progress.
    pub fn unresolved_pixels(&self) -> u64 {
        let area =
            |q: &GpuQuad| (q.own_x1 + 1).saturating_sub(q.x0) as u64 * (q.own_y1 + 1).saturating_sub(q.y0) as u64;
        self.active.iter().map(|&q| area(&self.owned(q))).sum()
    }

    /// The quads accepted for interpolation and those still to be judged, each with its own pixels. Once a
    /// round's sensors are done every corner of each is sensed, so interpolating them all fills the image: a
    /// preview of the render so far (the final image interpolates only [`Refinement::interpolated`]).
    pub fn coverage(&self) -> Vec<GpuQuad> {
        self.interpolated.iter().copied().chain(self.active.iter().map(|&q| self.owned(q))).collect()
    }

    /// No quad is left to judge.
    pub fn is_finished(&self) -> bool {
        self.active.is_empty()
    }

    /// Each pixel's light hint (`sensors::hints`), or none.
    pub fn hints(&self) -> &[u64] {
        &self.hints
    }

    /// Whether pixel `i` was sensed.
    pub fn is_sensed(&self, i: usize) -> bool {
        self.sensed[i]
    }
}

/// Corner coordinates after splitting `[a, b]` at its midpoint (unsplit when under two pixels wide).
fn split(a: u32, b: u32) -> Vec<u32> {
    if b - a > 1 { vec![a, (a + b) / 2, b] } else { vec![a, b] }
}

/// Fills the pixels quad `q` owns that were not sensed with `value(pixel, bilinear weights of the corners
/// (x0, y0), (x1, y0), (x0, y1), (x1, y1), R at those corners)`, marked interpolated.
fn fill_quad(
    radiance: &mut [Vec4],
    width: u32,
    q: &GpuQuad,
    mut value: impl FnMut(usize, [f32; 4], [Vec3; 4]) -> Vec3,
) {
    use crate::gpu_types::radiance_state::{INTERPOLATED, SENSED};
    let at = |x: u32, y: u32| (y * width + x) as usize;
    let corners = [at(q.x0, q.y0), at(q.x1, q.y0), at(q.x0, q.y1), at(q.x1, q.y1)].map(|c| radiance[c].truncate());
    for y in q.y0..=q.own_y1 {
        for x in q.x0..=q.own_x1 {
            let i = at(x, y);
            if radiance[i].w == SENSED {
                continue;
            }
            radiance[i] = value(i, weights(q, x, y), corners).extend(INTERPOLATED);
        }
    }
}

/// The bilinear weights of `q`'s corners (x0, y0), (x1, y0), (x0, y1), (x1, y1) at its pixel (x, y).
fn weights(q: &GpuQuad, x: u32, y: u32) -> [f32; 4] {
    let (w, h) = ((q.x1 - q.x0).max(1) as f32, (q.y1 - q.y0).max(1) as f32);
    let (fx, fy) = ((x - q.x0) as f32 / w, (y - q.y0) as f32 / h);
    [(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy]
}

/// Every pixel's visibilities as the render has them: `visibility` where `sensed`, and in the pixels each of
/// `quads` owns as the exact interpolation computes them from the corners (`measured_visibility`). For the
/// supersampling, whose samples take a neighbour's light (`supersample::donor`).
pub fn visibility_everywhere(
    visibility: &[Visibility],
    width: u32,
    quads: &[GpuQuad],
    sensed: impl Fn(usize) -> bool,
) -> Vec<Visibility> {
    let mut all = visibility.to_vec();
    for (q, seen) in quads.iter().zip(corner_visibility(visibility, width, quads)) {
        for y in q.y0..=q.own_y1 {
            for x in q.x0..=q.own_x1 {
                let i = (y * width + x) as usize;
                if !sensed(i) {
                    let weight = weights(q, x, y);
                    all[i] = std::array::from_fn(|g| measured_visibility(weight, seen.map(|corner| corner[g])));
                }
            }
        }
    }
    all
}

/// Each quad's corners' visibilities, corners (x0, y0), (x1, y0), (x0, y1), (x1, y1): what the exact
/// interpolation reads (`visibility` per pixel of an image `width` wide).
pub fn corner_visibility(visibility: &[Visibility], width: u32, quads: &[GpuQuad]) -> Vec<[Visibility; 4]> {
    let at = |x: u32, y: u32| visibility[(y * width + x) as usize];
    quads.iter().map(|q| [at(q.x0, q.y0), at(q.x1, q.y0), at(q.x0, q.y1), at(q.x1, q.y1)]).collect()
}

/// A group's visibility at a pixel of bilinear `weight`s from the corners that measured it (`seen` ≥ 0): their
/// weighted mean; on an edge whose two corners did not, the others' plain mean; none did: 1 (nothing says it
/// is hidden, as in the reduction). The shader's rule, `glsl/interpolate_exact.comp`.
fn measured_visibility(weight: [f32; 4], seen: [f32; 4]) -> f32 {
    let (mut weighted, mut total, mut plain, mut count) = (0.0, 0.0, 0.0, 0.0);
    for c in (0..4).filter(|&c| seen[c] >= 0.0) {
        (weighted, total, plain, count) =
            (weighted + weight[c] * seen[c], total + weight[c], plain + seen[c], count + 1.0);
    }
    if total > 0.0 {
        weighted / total
    } else if count > 0.0 {
        plain / count
    } else {
        1.0
    }
}

/// Σ weight · value over a quad's corners.
fn bilinear(weight: [f32; 4], values: [Vec3; 4]) -> Vec3 {
    (0..4).map(|c| weight[c] * values[c]).sum()
}

/// The CPU twin of `glsl/interpolate.comp`: fills each quad's own pixels that are not sensed.
pub fn interpolate_cpu(radiance: &mut [Vec4], width: u32, quads: &[GpuQuad]) {
    for q in quads {
        fill_quad(radiance, width, q, |_, weight, corners| bilinear(weight, corners));
    }
}

/// The CPU twin of `glsl/interpolate_exact.comp`: fills each quad's own pixels that are not sensed with each
/// light group's unoccluded light computed at the pixel (at a sensor lifted by `bias` along the normal, over
/// the hemisphere: `light::polygon`, the twin of the shader's formula) times its visibility interpolated from
/// the corners that measured it, plus the rest (`indirect`, R's part from the main layers) interpolated.
/// `corner_visibility`: one per quad, corners (x0, y0), (x1, y0), (x0, y1), (x1, y1).
pub fn interpolate_exact_cpu(
    (radiance, indirect): (&mut [Vec4], &[Vec4]),
    corner_visibility: &[[Visibility; 4]],
    (g, lights, bias): (&GBufferData, &Lights, f32),
    quads: &[GpuQuad],
) {
    let width = g.size.width;
    for (q, seen) in quads.iter().zip(corner_visibility) {
        let at = |x: u32, y: u32| (y * width + x) as usize;
        let rests = [at(q.x0, q.y0), at(q.x1, q.y0), at(q.x0, q.y1), at(q.x1, q.y1)].map(|c| indirect[c].truncate());
        fill_quad(radiance, width, q, |i, weight, corners| {
            let (position, n) = (g.position[i], g.normal[i].truncate());
            if position.w == 0.0 {
                return bilinear(weight, corners);
            }
            let e = lights.unoccluded(position.truncate() + n * bias, n);
            let direct: Vec3 = (0..lights.groups.len())
                .filter(|&group| e[group].max_element() > 0.0)
                .map(|group| e[group] * measured_visibility(weight, seen.map(|corner| corner[group])))
                .sum();
            bilinear(weight, rests) + direct / std::f32::consts::PI
        });
    }
}
