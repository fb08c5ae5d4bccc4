//! Rays: what the camera casts through a pixel, and the watertight ray–triangle test of Woop, Benthin and
//! Wald (JCGT 2013) that traces them: no ray slips through the shared edge of two triangles, which matters
//! for sensors looking at the seams of a closed room.

use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    /// Need not be unit length; `t` is measured in multiples of it.
    pub dir: Vec3,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Per-ray constants of the watertight test: the axis permutation and shear that map the ray onto +z, as
/// the three rows that take a point relative to the origin to the sheared frame (`x = p[kx] − sx·p[kz]`,
/// `y = p[ky] − sy·p[kz]`, `z = sz·p[kz]`). A row has a 1 (or `sz`) and `−s` on two axes and 0 on the third,
/// so its dot product rounds exactly as the formula does, without indexing a vector by a per-ray axis.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub origin: Vec3,
    rows: [Vec3; 3],
}

impl RayShear {
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let kz = d.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky); // keep the winding
        }
        let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
        let axis = |k: usize, value: f32| {
            let mut row = Vec3::ZERO;
            row[k] = value;
            row
        };
        let rows = [axis(kx, 1.0) + axis(kz, -sx), axis(ky, 1.0) + axis(kz, -sy), axis(kz, sz)];
        Self { origin: ray.origin, rows }
    }

    /// Distance along the ray to the triangle if hit within `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, v: &[Vec3; 3], t_max: f32) -> Option<f32> {
        let [rx, ry, rz] = self.rows;
        let a = v[0] - self.origin;
        let b = v[1] - self.origin;
        let c = v[2] - self.origin;
        let (ax, ay) = (a.dot(rx), a.dot(ry));
        let (bx, by) = (b.dot(rx), b.dot(ry));
        let (cx, cy) = (c.dot(rx), c.dot(ry));
        let mut u = cx * by - cy * bx;
        let mut w_v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || w_v == 0.0 || w == 0.0 {
            // On an edge in single precision: decide in double, as the paper prescribes.
            u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
            w_v = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
            w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
        }
        if (u < 0.0 || w_v < 0.0 || w < 0.0) && (u > 0.0 || w_v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + w_v + w;
        if det == 0.0 {
            return None;
        }
        let (az, bz, cz) = (a.dot(rz), b.dot(rz), c.dot(rz));
        let t_scaled = u * az + w_v * bz + w * cz;
        let t = t_scaled / det;
        (t > 0.0 && t < t_max).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_misses_outside_and_reports_distance() {
        let tri = [Vec3::new(-1.0, -1.0, 5.0), Vec3::new(1.0, -1.0, 5.0), Vec3::new(0.0, 1.0, 5.0)];
        let hit = RayShear::new(&Ray::new(Vec3::ZERO, Vec3::Z)).intersect(&tri, f32::INFINITY);
        assert!((hit.unwrap() - 5.0).abs() < 1e-6);
        assert!(RayShear::new(&Ray::new(Vec3::new(3.0, 0.0, 0.0), Vec3::Z)).intersect(&tri, f32::INFINITY).is_none());
        assert!(RayShear::new(&Ray::new(Vec3::ZERO, Vec3::Z)).intersect(&tri, 4.0).is_none(), "beyond t_max");
        assert!(RayShear::new(&Ray::new(Vec3::ZERO, -Vec3::Z)).intersect(&tri, f32::INFINITY).is_none(), "behind");
    }

    #[test]
    fn shared_edge_is_watertight() {
        // Two triangles sharing the diagonal of a quad; rays along the diagonal must hit at least one.
        let (a, b, c, d) =
            (Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(0.0, 1.0, 1.0));
        let t1 = [a, b, c];
        let t2 = [a, c, d];
        for i in 1..1000 {
            let s = i as f32 / 1000.0;
            // Aimed at the point (s, s) of the shared edge, from an oblique direction.
            let dir = Vec3::new(0.31, 0.17, 1.0);
            let ray = Ray::new(Vec3::new(s, s, 1.0) - dir, dir);
            let shear = RayShear::new(&ray);
            assert!(
                shear.intersect(&t1, f32::INFINITY).is_some() || shear.intersect(&t2, f32::INFINITY).is_some(),
                "leak at s={s}"
            );
        }
    }
}
