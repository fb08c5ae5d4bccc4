//! The emitters as a distribution for next-event estimation: a triangle is picked with probability
//! proportional to its power (`luminance(Ke)·area`), then a point uniformly on it. Bright and large
//! triangles get the samples, so a scene of thousands of emissive triangles costs a binary search, not a
//! sample per triangle.
//!
//! The pick inverts a cumulative table with the first coordinate and rescales what is left of that
//! coordinate within the picked triangle's interval (the "sample reuse" of pbrt §A.1), so the
//! stratification of the low-discrepancy net survives into the point on the triangle. The first coordinate
//! comes in 32-bit fixed point and the table is in f64, so even a triangle picked with probability 1e-6 keeps
//! 12 bits of its coordinate.

use glam::Vec3;

use crate::scene::Mesh;

/// Rec. 709 luminance: the power measure, as only the relative brightness of emitters matters.
pub const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

pub struct Lights {
    /// Mesh index of each emitting triangle.
    triangles: Vec<u32>,
    /// `cdf[k]`: probability of picking one of the first k emitters; `cdf[0] = 0`, the last is exactly 1.
    cdf: Vec<f64>,
    /// Per mesh triangle: probability density of a sampled point per unit area (`P_t / A_t`), 0 for
    /// triangles that do not emit.
    area_pdf: Vec<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Mesh index of the triangle.
    pub triangle: u32,
    pub point: Vec3,
}

impl Lights {
    /// The emitters of `mesh` (materials with `Ke > 0`); `None` when there are none.
    pub fn new(mesh: &Mesh) -> Option<Self> {
        let mut triangles = Vec::new();
        let mut power = Vec::new();
        for (i, t) in mesh.triangles.iter().enumerate() {
            let material = mesh.material_of(t.surface);
            if material.is_emitter() {
                triangles.push(i as u32);
                // Ke ≥ 0 with one channel > 0, so the luminance is > 0; an emission texture's mean may be
                // black where the texture is not quite: a floor keeps every emitter pickable (unbiased).
                let mean = mesh.mean_emission(i).dot(LUMINANCE).max(1e-3 * material.ke.dot(LUMINANCE));
                power.push(mean as f64 * area(&t.v));
            }
        }
        let total: f64 = power.iter().sum();
        if triangles.is_empty() || !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut cdf = Vec::with_capacity(power.len() + 1);
        let mut running = 0.0;
        cdf.push(0.0);
        for p in &power {
            running += p;
            cdf.push(running / total);
        }
        *cdf.last_mut().expect("one entry per emitter") = 1.0;
        let mut area_pdf = vec![0.0; mesh.triangles.len()];
        for (k, &i) in triangles.iter().enumerate() {
            area_pdf[i as usize] = (cdf[k + 1] - cdf[k]) / area(&mesh.triangles[i as usize].v);
        }
        Some(Self { triangles, cdf, area_pdf })
    }

    /// Emitting triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// A point on an emitter from the 32-bit fixed-point pair `u`: triangle `t` with probability
    /// `P_t`, then uniformly on it, so its density per unit area is [`Self::area_pdf`].
    pub fn sample(&self, mesh: &Mesh, u: (u32, u32)) -> LightSample {
        const SCALE: f64 = 1.0 / 4_294_967_296.0;
        let (u0, u1) = (u.0 as f64 * SCALE, u.1 as f64 * SCALE);
        // The last k with cdf[k] ≤ u0: never one of probability 0, whose interval is empty.
        let k = (self.cdf.partition_point(|&c| c <= u0) - 1).min(self.triangles.len() - 1);
        let reused = ((u0 - self.cdf[k]) / (self.cdf[k + 1] - self.cdf[k])).clamp(0.0, 1.0);
        let triangle = self.triangles[k];
        let v = mesh.triangles[triangle as usize].v.map(|p| p.as_dvec3());
        // Uniform on the triangle (Turk 1990; pbrt's square-root map): area-preserving and continuous.
        let s = reused.sqrt();
        let (b0, b1) = (1.0 - s, u1 * s);
        let point = v[0] * b0 + v[1] * b1 + v[2] * (1.0 - b0 - b1);
        LightSample { triangle, point: point.as_vec3() }
    }

    /// Density per unit area of [`Self::sample`]'s points on mesh triangle `triangle` (0 if it does not emit).
    pub fn area_pdf(&self, triangle: u32) -> f64 {
        self.area_pdf[triangle as usize]
    }
}

fn area(v: &[Vec3; 3]) -> f64 {
    let [a, b, c] = v.map(|p| p.as_dvec3());
    0.5 * (b - a).cross(c - a).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::sampling::ScrambledSobol;
    use crate::scene::builtin::{from_groups, rect};
    use crate::scene::{Camera, ImageSize, Material};

    fn mesh(groups: Vec<(&str, usize, Vec<[Vec3; 3]>)>, ke: [f32; 3]) -> Mesh {
        let material = |name: &str, ke: f32| Material::new(name, Vec3::splat(0.5), Vec3::splat(ke));
        let materials = ke.iter().enumerate().map(|(i, &k)| material(&format!("m{i}"), k)).collect();
        let camera = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 60.0).unwrap();
        from_groups(groups, materials, camera, ImageSize { width: 1, height: 1 }).mesh
    }

    #[test]
    fn picks_triangles_in_proportion_to_power_and_points_uniformly() {
        // A dim large light (Ke 1, area 4), a bright small one (Ke 8, area 1) and a wall that does not emit.
        let m = mesh(
            vec![
                ("dim", 0, rect(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z)),
                ("bright", 1, rect(Vec3::new(5.0, 0.0, 0.0), Vec3::X * 0.5, Vec3::Y * 0.5, Vec3::Z)),
                ("wall", 2, rect(Vec3::new(0.0, 0.0, -3.0), Vec3::X, Vec3::Y, Vec3::Z)),
            ],
            [1.0, 8.0, 0.0],
        );
        let lights = Lights::new(&m).unwrap();
        assert_eq!(lights.len(), 4);
        let net = ScrambledSobol::new(3);
        let n = 1 << 16;
        let (mut bright, mut centroid) = (0usize, Vec3::ZERO);
        for i in 0..n {
            let s = lights.sample(&m, net.bits(i));
            assert!(m.material_of(m.triangles[s.triangle as usize].surface).is_emitter());
            if s.point.x > 2.0 {
                bright += 1;
                centroid += s.point;
            }
        }
        // Power 4 : 8, so the bright light gets 2/3 of the samples, spread evenly over its square.
        let share = bright as f64 / n as f64;
        assert!((share - 2.0 / 3.0).abs() < 1e-3, "{share}");
        let centroid = centroid / bright as f32;
        assert!((centroid - Vec3::new(5.0, 0.0, 0.0)).length() < 2e-3, "{centroid}");
        // The densities integrate to 1 over the emitters: Σ P_t/A_t · A_t.
        let total: f64 =
            (0..m.triangles.len() as u32).map(|t| lights.area_pdf(t) * area(&m.triangles[t as usize].v)).sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        assert_eq!(lights.area_pdf(4), 0.0, "the wall is not a light");
    }

    #[test]
    fn no_emitters_means_no_light_table() {
        let m = mesh(vec![("wall", 0, rect(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z))], [0.0, 0.0, 0.0]);
        assert!(Lights::new(&m).is_none());
    }
}
