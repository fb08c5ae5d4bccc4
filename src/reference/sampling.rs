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
//!
//! The vertices of a path beyond its first draw from [`HashedStream`], counter-based uniform numbers: a
//! path's length is random, so its deeper dimensions have no fixed place in a net, and what they add is a
//! small, smooth part of the estimate where stratification buys little.

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

/// Uniform numbers as a pure function of (key, sample, depth, word): a counter-based generator built on
/// [`hash`], so a path's vertex `depth` draws the same numbers however the work is split over threads, and
/// two replicates (two keys) draw independent ones.
pub struct HashedStream {
    key: u64,
}

/// What one path vertex draws: a point on an emitter, a cosine direction, a Russian-roulette decision, a
/// direction towards the sky map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexSamples {
    /// 32-bit fixed point, as [`ScrambledSobol::bits`] (the light pick reuses the low digits).
    pub light: (u32, u32),
    /// In [0, 1)², as [`ScrambledSobol::point`].
    pub direction: Vec2,
    /// In [0, 1).
    pub roulette: f32,
    /// In [0, 1)², for `SkyMap::sample`.
    pub sky: Vec2,
}

impl HashedStream {
    pub fn new(key: u64) -> Self {
        Self { key: hash(key) }
    }

    /// The numbers of sample `sample`'s path vertex `depth`.
    pub fn vertex(&self, sample: u32, depth: u32) -> VertexSamples {
        let path = hash(self.key ^ sample as u64);
        let word = |k: u64| hash(path ^ ((depth as u64) << 2 | k));
        let (light, direction, roulette, sky) = (word(0), word(1), word(2), word(3));
        VertexSamples {
            light: (light as u32, (light >> 32) as u32),
            direction: Vec2::new(unit(direction as u32), unit((direction >> 32) as u32)),
            roulette: unit(roulette as u32),
            sky: Vec2::new(unit(sky as u32), unit((sky >> 32) as u32)),
        }
    }
}

/// A 32-bit fixed-point number as an f32 in [0, 1), keeping 24 bits so that it never rounds up to 1.0.
fn unit(v: u32) -> f32 {
    (v >> 8) as f32 * (1.0 / 16_777_216.0)
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
    fn hashed_streams_are_uniform_reproducible_and_independent() {
        let a = HashedStream::new(9);
        assert_eq!(a.vertex(3, 5), HashedStream::new(9).vertex(3, 5), "a pure function of its arguments");
        let (n, mut moments) = (1u32 << 14, [0f64; 4]);
        let (mut equal, mut cross) = (0, 0.0);
        let b = HashedStream::new(10);
        for i in 0..n {
            let v = a.vertex(i / 8, i % 8);
            let u = [v.direction.x, v.direction.y, v.roulette, v.light.0 as f32 / 4_294_967_296.0];
            assert!(u.iter().all(|x| (0.0..1.0).contains(x)), "{u:?}");
            for (m, x) in moments.iter_mut().zip(u) {
                *m += x as f64;
            }
            let w = b.vertex(i / 8, i % 8);
            equal += usize::from(w == v);
            cross += (v.roulette as f64 - 0.5) * (w.roulette as f64 - 0.5);
        }
        // Means of 2¹⁴ uniforms: 0.5 within 5 standard errors (1/√(12·2¹⁴) = 0.0023).
        for m in moments {
            assert!((m / n as f64 - 0.5).abs() < 0.012, "{moments:?}");
        }
        assert_eq!(equal, 0, "two keys draw different numbers");
        // Two keys uncorrelated: the covariance is 0 within 5 standard errors (1/(12·√2¹⁴) = 6.5e-4).
        assert!((cross / n as f64).abs() < 3.3e-3, "{cross}");
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
