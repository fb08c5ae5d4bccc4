//! Texel weights: the exact projected solid angle `∫ cosθ dω` of each sensor-map texel (docs/DESIGN.md §2).
//!
//! With them `R = (1/π) Σ Ck·w` is a quadrature of `(1/π) ∫ Ck cosθ dω` whose result does not depend on the
//! map size, only its noise does. The paper's cross-product formula (its eq. 4) approximates the same
//! quantity; here it is integrated in closed form:
//!
//! - front texel `[x0,x1]×[y0,y1]` of the plane `z = 1`: `∫∫ dx dy / (1+x²+y²)²`, antiderivative `G` below;
//! - side texel `[u0,u1]×[v0,v1]` of a side face (`v` ≥ 0 the height above the horizon):
//!   `∫∫ v du dv / (1+u²+v²)²`, antiderivative `H(u,v) = −atan(u/√(1+v²)) / (2√(1+v²))`.
//!
//! Computed in f64 once per (kind, rd) and uploaded as f32.

use glam::{Vec3, Vec4};

use super::SensorKind;
use super::frame::SensorFrame;
use super::layout::{LayerKind, layers, views};

/// `∂²G/∂x∂y = 1/(1+x²+y²)²`.
pub fn front_antiderivative(x: f64, y: f64) -> f64 {
    let (ax, ay) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    0.5 * (x / ax * (y / ax).atan() + y / ay * (x / ay).atan())
}

/// `∂²H/∂u∂v = v/(1+u²+v²)²`.
pub fn side_antiderivative(u: f64, v: f64) -> f64 {
    let a = (1.0 + v * v).sqrt();
    -(u / a).atan() / (2.0 * a)
}

fn rectangle(f: fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
}

/// NDC interval `[lo, hi]` of texel `k` of `rd` (texel edges at `-1 + 2k/rd`).
fn ndc(k: u32, rd: u32) -> (f64, f64) {
    let step = 2.0 / rd as f64;
    (-1.0 + step * k as f64, -1.0 + step * (k + 1) as f64)
}

/// Weights of one layer, row-major (`rd × rd`).
pub fn layer_weights(kind: LayerKind, rd: u32) -> Vec<f64> {
    let mut w = Vec::with_capacity((rd * rd) as usize);
    for i in 0..rd {
        let (y0, y1) = ndc(i, rd);
        for j in 0..rd {
            let (x0, x1) = ndc(j, rd);
            w.push(match kind {
                LayerKind::Front { s } => rectangle(front_antiderivative, s * x0, s * x1, s * y0, s * y1),
                // Rows never straddle the horizon (rd is even), so |y| is monotonic on each texel.
                LayerKind::SidePair => {
                    let (v0, v1) = (y0.abs().min(y1.abs()), y0.abs().max(y1.abs()));
                    rectangle(side_antiderivative, x0, x1, v0, v1)
                }
            });
        }
    }
    w
}

/// Weights of every layer of a sensor, layer-major (layer, row, column).
pub fn sensor_weights(kind: SensorKind, rd: u32) -> Vec<f64> {
    layers(kind).into_iter().flat_map(|layer| layer_weights(layer, rd)).collect()
}

/// Per texel of a sensor's main layers (layer, row, column, as [`sensor_weights`]): the unit direction
/// through its centre in the sensor's frame (x along t, y along b, z along n), and in w the solid angle it
/// covers (`area / |d|³` of its square on its view's plane at distance 1). The reduction looks the sky map
/// up along it, averaged over that solid angle, where the texel sees no geometry.
pub fn texel_directions(kind: SensorKind, rd: u32) -> Vec<Vec4> {
    let frame = SensorFrame { origin: Vec3::ZERO, t: Vec3::X, b: Vec3::Y, n: Vec3::Z };
    let views = views(kind);
    let mut out = Vec::with_capacity(layers(kind).len() * (rd * rd) as usize);
    for layer in 0..layers(kind).len() as u32 {
        let in_layer: Vec<_> = views.iter().filter(|v| v.layer == layer).collect();
        for row in 0..rd {
            let ndc_y = (row as f32 + 0.5) * 2.0 / rd as f32 - 1.0;
            for column in 0..rd {
                let ndc_x = (column as f32 + 0.5) * 2.0 / rd as f32 - 1.0;
                // A side pair's two views share the layer, each kept above the horizon: the texel is the
                // one whose direction is.
                let view =
                    (in_layer.iter()).find(|v| frame.direction(v, ndc_x, ndc_y).z >= 0.0).unwrap_or(&in_layer[0]);
                let s = (view.fov_deg.to_radians() * 0.5).tan();
                let length2 = 1.0 + (ndc_x * s).powi(2) + (ndc_y * s).powi(2);
                let area = (2.0 * s / rd as f32).powi(2);
                out.push(frame.direction(view, ndc_x, ndc_y).extend(area / length2.powf(1.5)));
            }
        }
    }
    out
}

/// `Σ w` over a sensor, exact: π for a hemicube, `4·G(S, S)` for a frustum of half-width `S`.
pub fn total(kind: SensorKind) -> f64 {
    match kind {
        SensorKind::Hemicube => std::f64::consts::PI,
        SensorKind::Frustum { fov_deg } => {
            let s = (fov_deg as f64 * 0.5).to_radians().tan();
            4.0 * front_antiderivative(s, s)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn sum(kind: SensorKind, rd: u32) -> f64 {
        sensor_weights(kind, rd).iter().sum()
    }

    /// Each texel's direction and solid angle agree with its weight (`w ≈ cosθ·dω`), the directions cover
    /// the hemisphere once (`Σ dω ≈ 2π`), and every direction lies above the horizon.
    #[test]
    fn texel_directions_agree_with_the_weights_and_cover_the_hemisphere() {
        for kind in [SensorKind::Hemicube, SensorKind::Frustum { fov_deg: 135.0 }] {
            let rd = 32;
            let (w, d) = (sensor_weights(kind, rd), texel_directions(kind, rd));
            assert_eq!(w.len(), d.len());
            for (w, d) in w.iter().zip(&d) {
                assert!(d.z > 0.0 && (d.truncate().length() - 1.0).abs() < 1e-5, "{d}");
                assert!((d.z as f64 * d.w as f64 / w - 1.0).abs() < 0.01, "{w} vs {}", d.z * d.w);
            }
            if kind == SensorKind::Hemicube {
                let omega: f64 = d.iter().map(|d| d.w as f64).sum();
                assert!((omega / (2.0 * PI) - 1.0).abs() < 1e-3, "{omega}");
            }
        }
    }

    #[test]
    fn hemicube_weights_sum_to_pi() {
        for rd in [2, 16, 64, 256] {
            assert!((sum(SensorKind::Hemicube, rd) - PI).abs() < 1e-6, "rd {rd}: {}", sum(SensorKind::Hemicube, rd));
        }
    }

    #[test]
    fn frustum_135_weights_sum_to_0_8774_pi() {
        let kind = SensorKind::Frustum { fov_deg: 135.0 };
        for rd in [3, 64, 256] {
            assert!((sum(kind, rd) - total(kind)).abs() < 1e-9);
        }
        assert!((total(kind) / PI - 0.8774).abs() < 5e-5, "{}", total(kind) / PI);
    }

    /// The closed forms against brute-force midpoint quadrature of the integrands.
    #[test]
    fn closed_forms_match_quadrature() {
        let quad = |f: &dyn Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64| {
            let n = 400;
            let (dx, dy) = ((x1 - x0) / n as f64, (y1 - y0) / n as f64);
            let mut s = 0.0;
            for i in 0..n {
                for j in 0..n {
                    s += f(x0 + (i as f64 + 0.5) * dx, y0 + (j as f64 + 0.5) * dy);
                }
            }
            s * dx * dy
        };
        let front = |x: f64, y: f64| 1.0 / (1.0 + x * x + y * y).powi(2);
        let side = |u: f64, v: f64| v / (1.0 + u * u + v * v).powi(2);
        for (x0, x1, y0, y1) in [(-1.0, 1.0, -1.0, 1.0), (0.2, 0.7, -2.0, -1.5), (-2.4, 2.4, 0.1, 0.3)] {
            let exact = rectangle(front_antiderivative, x0, x1, y0, y1);
            assert!((exact - quad(&front, x0, x1, y0, y1)).abs() < 1e-5 * exact.max(1e-3));
        }
        for (u0, u1, v0, v1) in [(-1.0, 1.0, 0.0, 1.0), (0.5, 0.75, 0.25, 0.5)] {
            let exact = rectangle(side_antiderivative, u0, u1, v0, v1);
            assert!((exact - quad(&side, u0, u1, v0, v1)).abs() < 1e-5 * exact.max(1e-3));
        }
    }

    /// The paper's eq. 4 (cross product of the projected texel edges) approximates these weights and agrees
    /// with them as the texels shrink.
    #[test]
    fn paper_cross_product_formula_converges_to_exact_weights() {
        let s = (67.5f64).to_radians().tan();
        let project = |x: f64, y: f64| {
            let len = (x * x + y * y + 1.0).sqrt();
            (x / len, y / len)
        };
        let worst_error = |rd: u32| {
            let exact = layer_weights(LayerKind::Front { s }, rd);
            let mut worst: f64 = 0.0;
            for i in 0..rd {
                for j in 0..rd {
                    let x = |k: u32| 2.0 * s * (k as f64 / rd as f64 - 0.5);
                    let v0 = project(x(j), x(i));
                    let v1 = project(x(j + 1), x(i));
                    let v2 = project(x(j), x(i + 1));
                    let d = ((v1.0 - v0.0) * (v2.1 - v0.1) - (v1.1 - v0.1) * (v2.0 - v0.0)).abs();
                    let e = exact[(i * rd + j) as usize];
                    worst = worst.max((d - e).abs() / e);
                }
            }
            worst
        };
        let (coarse, fine) = (worst_error(16), worst_error(128));
        assert!(fine < coarse / 4.0, "eq. 4 error {coarse} at rd 16, {fine} at rd 128");
        assert!(fine < 0.05);
    }
}
