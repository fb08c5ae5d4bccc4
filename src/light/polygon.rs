//! The projected solid angle of a polygon seen from a point: irradiance from a polygon of unit radiance,
//! exact, in f64. It is the CPU twin of the exact unoccluded emitter term: `R = Ke/π · Ω⊥` for an emitter
//! polygon that nothing hides.
//!
//! **Formula** (Lambert 1760; Arvo 1995, "Applications of Irradiance Tensors", eq. 7). With `rᵢ` the
//! polygon's vertices relative to the receiving point `x`, and `n` its unit normal,
//!
//! ```text
//! Ω⊥ = ∫_polygon cosθ dω = ½ Σᵢ Θᵢ · n·Γᵢ,   Θᵢ = ∠(rᵢ, rᵢ₊₁),   Γᵢ = (rᵢ₊₁ × rᵢ) / |rᵢ₊₁ × rᵢ|
//! ```
//!
//! (Stokes' theorem on the sphere: each edge contributes the angle it subtends times the cosine between `n`
//! and the normal of the plane through `x` and the edge.) `cosθ` is signed, so the polygon must first be
//! clipped to the sensor's domain; the sum is then over the clipped polygon's edges.
//!
//! **Sign and side.** Vertices are in the scene's order: counter-clockwise seen from the front, the front
//! normal being `(v₁ − v₀) × (v₂ − v₀)` as for [`crate::scene::Triangle`]. Emitters are one-sided and emit
//! from the front only (DESIGN.md §1), so a polygon whose front does not face `x` gives 0; one that does,
//! wound that way, makes every term above positive-oriented, and the result is ≥ 0.
//!
//! **Domain** (the sensor's, DESIGN.md §2): the half-space above the tangent plane for the hemicube, or the
//! paper's square frustum — the four planes through `x` that cut the plane `z = 1` of the sensor frame
//! `(t, b, n)` along `|x| = s`, `|y| = s`, `s = tan(fov/2)`. Each plane goes through `x`, so clipping the
//! polygon by it is the same as clipping its cone of directions. A triangle clipped by k planes keeps at most
//! 3 + k vertices (7 for the frustum): a fixed-size array on the GPU.

use glam::DVec3;

/// The directions a sensor integrates over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Domain {
    /// `n·ω > 0`: the full-hemisphere (hemicube) sensor.
    Hemisphere,
    /// The paper's single view: `|t·ω| ≤ s·(n·ω)` and `|b·ω| ≤ s·(n·ω)`, `s = tan(fov/2)` (`half_width`).
    Frustum { half_width: f64 },
}

/// Where the sensor sits and how it is turned: `t, b, n` orthonormal, `n` the surface's normal. For the
/// hemisphere only `n` matters; the frustum's square also turns with `t` and `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    pub origin: DVec3,
    pub t: DVec3,
    pub b: DVec3,
    pub n: DVec3,
}

impl Receiver {
    /// The planes through the origin, as normals `m` (inside: `m·r ≥ 0`), that bound `domain`.
    pub fn clip_planes(&self, domain: Domain) -> Vec<DVec3> {
        match domain {
            Domain::Hemisphere => vec![self.n],
            Domain::Frustum { half_width: s } => {
                vec![self.n * s - self.t, self.n * s + self.t, self.n * s - self.b, self.n * s + self.b]
            }
        }
    }
}

/// Unit normal of a planar polygon's front side (Newell's method, robust for any simple polygon); zero when
/// it has no area.
pub fn front_normal(polygon: &[DVec3]) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for (i, &a) in polygon.iter().enumerate() {
        sum += a.cross(polygon[(i + 1) % polygon.len()]);
    }
    sum.normalize_or_zero()
}

/// `Ω⊥`, the projected solid angle (steradians, 0 … π) of the part of `polygon` inside `domain` seen from
/// `receiver`, if its front faces the receiver; 0 otherwise. Irradiance from a uniform Lambertian polygon of
/// radiance `L` is `L·Ω⊥`; the sensor estimator's `R` is `L·Ω⊥/π`. Nothing occludes: this is the polygon
/// alone.
pub fn projected_solid_angle(receiver: &Receiver, domain: Domain, polygon: &[DVec3]) -> f64 {
    if polygon.len() < 3 {
        return 0.0;
    }
    let normal = front_normal(polygon);
    if normal.dot(receiver.origin - polygon[0]) <= 0.0 {
        return 0.0; // seen from behind or edge-on: one-sided emitters send nothing this way
    }
    lambert(&clip(receiver, domain, polygon), receiver.n)
}

/// The polygon's vertices relative to the receiver's origin, clipped to `domain` (Sutherland–Hodgman against
/// each plane through the origin). Fewer than 3 vertices: nothing of it is inside.
pub fn clip(receiver: &Receiver, domain: Domain, polygon: &[DVec3]) -> Vec<DVec3> {
    let mut vertices: Vec<DVec3> = polygon.iter().map(|&v| v - receiver.origin).collect();
    for m in receiver.clip_planes(domain) {
        vertices = clip_half_space(&vertices, m);
        if vertices.len() < 3 {
            return Vec::new();
        }
    }
    vertices
}

/// Keeps the part of the polygon (relative to the origin) with `m·r ≥ 0`.
fn clip_half_space(polygon: &[DVec3], m: DVec3) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(polygon.len() + 1);
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let (da, db) = (m.dot(a), m.dot(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            // Exactly one side is inside, so da − db ≠ 0.
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

/// Lambert's sum `½ Σ Θᵢ n·Γᵢ` over the edges of a polygon given relative to the receiving point, wound
/// counter-clockwise seen from its front, which faces the point: `∫ n·ω dω` over its solid angle, signed.
pub fn lambert(vertices: &[DVec3], n: DVec3) -> f64 {
    if vertices.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for (i, &a) in vertices.iter().enumerate() {
        let b = vertices[(i + 1) % vertices.len()];
        let c = b.cross(a);
        let length = c.length();
        if length > 0.0 {
            // atan2 keeps Θ accurate for nearly parallel and nearly opposite vertices, where acos does not.
            sum += length.atan2(a.dot(b)) * n.dot(c) / length;
        }
    }
    0.5 * sum
}

/// Irradiance/π from a rectangle `[x0, x1] × [y0, y1]` at height `h`, parallel to the receiver and facing it
/// (coordinates relative to the receiving point): the form factor of Howell's catalogue (C-11) for a
/// corner-aligned rectangle, combined with signs. An independent closed form to check
/// [`projected_solid_angle`] and the oracle against.
pub fn parallel_rectangle(x0: f64, x1: f64, y0: f64, y1: f64, h: f64) -> f64 {
    let corner = |a: f64, b: f64| {
        let (a, b) = (a / h, b / h);
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI)
    };
    corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    fn receiver_up(origin: DVec3) -> Receiver {
        Receiver { origin, t: DVec3::X, b: DVec3::NEG_Z, n: DVec3::Y }
    }

    /// A rectangle `center ± u ± v` wound so that its front faces `facing`.
    fn rect(center: DVec3, u: DVec3, v: DVec3, facing: DVec3) -> Vec<DVec3> {
        let c = vec![center - u - v, center + u - v, center + u + v, center - u + v];
        if u.cross(v).dot(facing) < 0.0 { c.into_iter().rev().collect() } else { c }
    }

    /// Shirley & Chiu's concentric map, in f64: a uniform grid on the square becomes cosine-distributed
    /// directions, so π × (fraction of grid points that see the polygon inside the domain) is `Ω⊥`.
    fn cosine_direction(u: f64, v: f64) -> DVec3 {
        let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
        let (r, phi) = if a.abs() > b.abs() { (a, PI / 4.0 * (b / a)) } else { (b, PI / 2.0 - PI / 4.0 * (a / b)) };
        let (x, y) = (r * phi.cos(), r * phi.sin());
        DVec3::new(x, y, (1.0 - x * x - y * y).max(0.0).sqrt())
    }

    /// Brute-force `Ω⊥` by a `k × k` midpoint grid of cosine-distributed directions, each tested against the
    /// (convex) polygon's front and the domain independently of the clipping code. Its error is O(1/k), from
    /// the grid cells the polygon's outline cuts.
    fn quadrature(receiver: &Receiver, domain: Domain, polygon: &[DVec3], k: usize) -> f64 {
        let normal = front_normal(polygon);
        let mut hits = 0usize;
        for i in 0..k {
            for j in 0..k {
                let l = cosine_direction((i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64);
                if let Domain::Frustum { half_width: s } = domain
                    && (l.x.abs() > s * l.z || l.y.abs() > s * l.z)
                {
                    continue;
                }
                let d = receiver.t * l.x + receiver.b * l.y + receiver.n * l.z;
                let facing = normal.dot(d);
                if facing >= 0.0 {
                    continue; // parallel to it or reaching its back
                }
                let t = normal.dot(polygon[0] - receiver.origin) / facing;
                if t <= 0.0 {
                    continue;
                }
                let p = receiver.origin + d * t;
                let inside = (0..polygon.len()).all(|e| {
                    let (a, b) = (polygon[e], polygon[(e + 1) % polygon.len()]);
                    (b - a).cross(p - a).dot(normal) >= 0.0
                });
                hits += inside as usize;
            }
        }
        PI * hits as f64 / (k * k) as f64
    }

    #[test]
    fn rectangles_parallel_to_the_receiver_match_the_form_factor_to_rounding() {
        let receiver = receiver_up(DVec3::ZERO);
        for (cx, cz, hw, hd, h) in [(0.0, 0.0, 0.5, 0.5, 1.0), (0.7, -0.3, 0.2, 1.5, 0.4), (5.0, 2.0, 0.05, 0.05, 2.0)]
        {
            let light = rect(DVec3::new(cx, h, cz), DVec3::X * hw, DVec3::Z * hd, DVec3::NEG_Y);
            let exact = PI * parallel_rectangle(cx - hw, cx + hw, cz - hd, cz + hd, h);
            let omega = projected_solid_angle(&receiver, Domain::Hemisphere, &light);
            assert!((omega - exact).abs() < 1e-12 * exact.max(1.0), "{omega} vs {exact}");
        }
    }

    #[test]
    fn an_infinite_plane_above_gives_pi_and_the_frustum_gives_4_g_s_s() {
        let receiver = receiver_up(DVec3::ZERO);
        let plane = rect(DVec3::Y, DVec3::X * 1e7, DVec3::Z * 1e7, DVec3::NEG_Y);
        let full = projected_solid_angle(&receiver, Domain::Hemisphere, &plane);
        assert!((full - PI).abs() < 1e-6, "{full}");
        // DESIGN.md §2: the 135° frustum sees 4·G(s, s) = 0.8774·π of the cosine-weighted hemisphere.
        let s = (67.5f64).to_radians().tan();
        let g = |x: f64, y: f64| {
            let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
            0.5 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
        };
        let frustum = projected_solid_angle(&receiver, Domain::Frustum { half_width: s }, &plane);
        assert!((frustum - 4.0 * g(s, s)).abs() < 1e-6, "{frustum} vs {}", 4.0 * g(s, s));
        assert!((frustum / PI - 0.8774).abs() < 1e-4);
    }

    #[test]
    fn a_light_seen_from_behind_or_edge_on_gives_zero() {
        let receiver = receiver_up(DVec3::ZERO);
        let facing_up = rect(DVec3::Y, DVec3::X * 0.5, DVec3::Z * 0.5, DVec3::Y);
        assert_eq!(projected_solid_angle(&receiver, Domain::Hemisphere, &facing_up), 0.0);
        let edge_on = rect(DVec3::new(0.0, 1.0, 0.0), DVec3::X * 0.5, DVec3::Y * 0.5, DVec3::Z);
        let receiver_in_plane = receiver_up(DVec3::new(0.0, 0.5, 0.0));
        assert_eq!(projected_solid_angle(&receiver_in_plane, Domain::Hemisphere, &edge_on), 0.0);
        // …and wholly below the horizon, front facing the point: nothing inside the domain.
        let below = rect(DVec3::NEG_Y, DVec3::X * 0.5, DVec3::Z * 0.5, DVec3::Y);
        assert_eq!(projected_solid_angle(&receiver, Domain::Hemisphere, &below), 0.0);
    }

    /// Clipped and unclipped cases against the brute-force quadrature (k = 2048: 4 M directions, error
    /// O(1/k) ≈ 1e-3 of the value at worst; observed below 3e-4).
    #[test]
    fn clipped_polygons_match_brute_force_quadrature() {
        let tilted = Receiver {
            origin: DVec3::new(0.1, 0.2, -0.3),
            t: DVec3::new(0.0, 0.6, 0.8),
            b: DVec3::new(0.6, -0.64, 0.48),
            n: DVec3::new(0.8, 0.48, -0.36),
        };
        let level = receiver_up(DVec3::ZERO);
        let s135 = Domain::Frustum { half_width: (67.5f64).to_radians().tan() };
        let s90 = Domain::Frustum { half_width: 1.0 };
        let triangle = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| vec![DVec3::from(a), DVec3::from(b), DVec3::from(c)];
        let cases: Vec<(&str, Receiver, Domain, Vec<DVec3>)> = vec![
            // A wall beside the point, its front towards it, reaching from below the horizon to above it.
            (
                "triangle straddling the horizon",
                level,
                Domain::Hemisphere,
                triangle([0.5, -0.6, -0.4], [0.5, 0.8, -0.2], [0.5, -0.3, 0.7]),
            ),
            ("quad straddling the horizon, tilted receiver", tilted, Domain::Hemisphere, {
                let centre = tilted.origin + tilted.t * 0.8 + tilted.n * 0.1;
                rect(centre, tilted.b * 0.4, tilted.n * 0.5, -tilted.t)
            }),
            // Crossing the plane x = s·y of the 135° frustum (s = 2.414 at height 1).
            (
                "triangle straddling the 135° frustum's edge",
                level,
                s135,
                triangle([1.6, 1.0, 0.2], [3.4, 1.0, -0.5], [2.2, 1.0, -1.0]),
            ),
            (
                "triangle across two edges of a 90° frustum",
                level,
                s90,
                triangle([0.5, 1.0, -0.4], [1.8, 1.0, -1.9], [0.4, 1.0, -2.0]),
            ),
            (
                "rectangle wholly inside",
                tilted,
                s135,
                rect(tilted.origin + tilted.n, tilted.t * 0.3, tilted.b * 0.2, -tilted.n),
            ),
        ];
        for (name, receiver, domain, polygon) in cases {
            // Wind each to face the receiver (emitters are one-sided).
            let facing = front_normal(&polygon).dot(receiver.origin - polygon[0]) > 0.0;
            let polygon: Vec<DVec3> = if facing { polygon } else { polygon.into_iter().rev().collect() };
            let exact = projected_solid_angle(&receiver, domain, &polygon);
            let brute = quadrature(&receiver, domain, &polygon, 2048);
            let unclipped = lambert(&polygon.iter().map(|&v| v - receiver.origin).collect::<Vec<_>>(), receiver.n);
            eprintln!("{name}: Ω⊥ {exact:.6}, quadrature {brute:.6}, unclipped {unclipped:.6}");
            assert!(exact > 0.01, "{name}: the case is not vacuous");
            assert!((exact - brute).abs() < 1e-3 * exact, "{name}: {exact} vs quadrature {brute}");
            if name.contains("straddling") {
                assert!((unclipped - exact).abs() > 0.01 * exact, "{name}: clipping did nothing");
            }
        }
    }
}
