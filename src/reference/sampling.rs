//! Deterministic low-discrepancy sampling: the 2D Sobol (0,2)-sequence with nested uniform (Owen)
//! scrambling, mapped to cosine-weighted directions by Shirley & Chiu's concentric disk. Every sample set is
//! a pure function of (seed, pixel, replicate), so renders are bit-reproducible.
//!
//! Owen scrambling rather than a random digital shift (XOR of one mask): the shift leaves the digits below
//! the net's resolution equal for every point, so whatever reads those digits (picking one of thousands of
//! lights by a coordinate, then reusing the rest of it for the point on that light) sees the same value in
//! every sample of a replicate: unbiased, but its error and its replicate noise estimate then stop falling
//! with the sample count. Owen scrambling randomises every digit by a hash of the digits above it, so each
//! point is uniform within its stratum and the strata independent (Owen 1995; variance `O(N⁻³)` for smooth
//! integrands, never worse than plain Monte Carlo).

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

/// Nested uniform scrambling of a 32-bit fixed-point coordinate: each bit is flipped by a hash of the bits
/// above it, which keeps every net a net. The hash is Laine & Karras' (2011) on the reversed bits, as in
/// Burley 2020 ("Practical Hash-based Owen Scrambling"), with Vegdahl's 2021 constants: in the reversed word
/// each step only lets lower bits act on higher ones (`x·even`, `+`, `·odd`), which is what makes it nested.
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    let mut x = x.reverse_bits();
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x.reverse_bits()
}

/// `n` points of an Owen-scrambled 2D Sobol net in [0, 1)², scrambled by `key`.
pub struct ScrambledSobol {
    seeds: (u32, u32),
}

impl ScrambledSobol {
    pub fn new(key: u64) -> Self {
        let h = hash(key);
        Self { seeds: (h as u32, (h >> 32) as u32) }
    }

    pub fn point(&self, i: u32) -> Vec2 {
        let (x, y) = self.bits(i);
        const SCALE: f32 = 1.0 / 4_294_967_296.0;
        // Keep 24 bits so that the f32 never rounds up to 1.0.
        let to_unit = |v: u32| ((v >> 8) << 8) as f32 * SCALE;
        Vec2::new(to_unit(x), to_unit(y))
    }

    /// Point `i` in 32-bit fixed point (`x / 2³²`), for callers that need more than an f32's 24 bits: picking
    /// one of many lights and reusing the rest of the number within it.
    pub fn bits(&self, i: u32) -> (u32, u32) {
        let (x, y) = sobol_2d(i);
        (owen_scramble(x, self.seeds.0), owen_scramble(y, self.seeds.1))
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
        for key in [42, 7, u64::MAX] {
            let sampler = ScrambledSobol::new(key);
            for a in 0..=8 {
                let b = 8 - a;
                let mut seen = vec![0u32; 256];
                for i in 0..256 {
                    let p = sampler.point(i);
                    let cell = ((p.x * (1 << a) as f32) as usize) * (1 << b) + (p.y * (1 << b) as f32) as usize;
                    seen[cell] += 1;
                }
                assert!(seen.iter().all(|&c| c == 1), "key {key}: not stratified in 2^{a} x 2^{b}");
            }
        }
    }

    #[test]
    fn digits_below_the_net_resolution_are_random_per_point() {
        // Where each of 256 points sits inside its 1/256 interval: uniform (variance 1/12) after Owen
        // scrambling; a digital shift would put them all at the same place (variance 0).
        let sampler = ScrambledSobol::new(5);
        for coordinate in [0, 1] {
            let within: Vec<f64> = (0..256)
                .map(|i| {
                    let (x, y) = sampler.bits(i);
                    let v = if coordinate == 0 { x } else { y };
                    (v << 8) as f64 / 4_294_967_296.0
                })
                .collect();
            let mean = within.iter().sum::<f64>() / 256.0;
            let variance = within.iter().map(|w| (w - mean) * (w - mean)).sum::<f64>() / 255.0;
            assert!((variance - 1.0 / 12.0).abs() < 0.02, "coordinate {coordinate}: variance {variance}");
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
