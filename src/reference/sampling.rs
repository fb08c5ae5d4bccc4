//! Deterministic low-discrepancy sampling: the 2D Sobol (0,2)-sequence with random digit scrambling
//! (Kollig & Keller 2002), mapped to cosine-weighted directions by Shirley & Chiu's concentric disk.
//! Every sample set is a pure function of (seed, pixel, replicate), so renders are bit-reproducible.

use glam::{Vec2, Vec3};

/// Point `i` of the 2D Sobol sequence as 32-bit fixed point: dimension 0 is the van der Corput sequence,
/// dimension 1 uses the generator matrix of Sobol's second dimension.
pub fn sobol_2d(i: u32) -> (u32, u32) {
    let x = i.reverse_bits();
    let (mut y, mut v, mut k) = (0u32, 1u32 << 31, i);
    while k != 0 {
        if k & 1 != 0 {
            y ^= v;
        }
        k >>= 1;
        v ^= v >> 1;
    }
    (x, y)
}

/// A 64-bit mix (SplitMix64's finaliser): decorrelates seeds that differ in a few bits.
pub fn hash(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// `n` points of a scrambled 2D Sobol net in [0, 1)², scrambled by `key` (XOR of the digits keeps it a net).
pub struct ScrambledSobol {
    mask: (u32, u32),
}

impl ScrambledSobol {
    pub fn new(key: u64) -> Self {
        let h = hash(key);
        Self { mask: (h as u32, (h >> 32) as u32) }
    }

    pub fn point(&self, i: u32) -> Vec2 {
        let (x, y) = sobol_2d(i);
        const SCALE: f32 = 1.0 / 4_294_967_296.0;
        // Keep 24 bits so that the f32 never rounds up to 1.0.
        let to_unit = |v: u32| ((v >> 8) << 8) as f32 * SCALE;
        Vec2::new(to_unit(x ^ self.mask.0), to_unit(y ^ self.mask.1))
    }
}

/// Shirley & Chiu's area-preserving map of the unit square onto the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let p = u * 2.0 - Vec2::ONE;
    if p == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, phi) = if p.x.abs() > p.y.abs() {
        (p.x, std::f32::consts::FRAC_PI_4 * (p.y / p.x))
    } else {
        (p.y, std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (p.x / p.y))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// A direction in the local frame (z up) distributed with density cosθ/π (Malley's method).
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    Vec3::new(d.x, d.y, (1.0 - d.length_squared()).max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol_is_a_02_net() {
        // Any 2^a × 2^b grid of elementary intervals with a + b = 8 holds exactly one of the first 256 points.
        let sampler = ScrambledSobol::new(42);
        for a in 0..=8 {
            let b = 8 - a;
            let mut seen = vec![0u32; 256];
            for i in 0..256 {
                let p = sampler.point(i);
                let cell = ((p.x * (1 << a) as f32) as usize) * (1 << b) + (p.y * (1 << b) as f32) as usize;
                seen[cell] += 1;
            }
            assert!(seen.iter().all(|&c| c == 1), "not stratified in 2^{a} x 2^{b}");
        }
    }

    #[test]
    fn cosine_directions_have_mean_cosine_two_thirds() {
        // E[cosθ] under the density cosθ/π over the hemisphere is 2/3.
        let sampler = ScrambledSobol::new(1);
        let n = 4096;
        let mean: f32 = (0..n).map(|i| cosine_hemisphere(sampler.point(i)).z).sum::<f32>() / n as f32;
        assert!((mean - 2.0 / 3.0).abs() < 1e-3, "{mean}");
        assert!((0..n).all(|i| (cosine_hemisphere(sampler.point(i)).length() - 1.0).abs() < 1e-5));
    }
}
