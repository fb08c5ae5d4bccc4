//! The transport between the cache's entries, rasterised once (docs/DESIGN.md §10): what each entry's
//! sensor sees of every other, as a sparse row of (value, weight) — the hemicube form factors of classic
//! radiosity (Cohen & Greenberg 1985) — so that the bounces after the first are sparse products on the host
//! instead of sensing every entry again.
//!
//! A sensor drawn with `CacheRead::Entries` leaves in each texel of its main layers the index of the cache
//! value the texel reads (`glsl/sensor_shade.glsl`), which is exactly what a texel sees of the cache when
//! drawn with its values: the value at that index, constant over an entry's piece. So with `w` a texel's
//! projected solid angle (`sensors::weights`), the R the values `v` send to the sensor is
//! `(1/π) Σ_texels w·v[index]`, and a row holds those weights summed per index. The rows are the same at
//! every bounce: `R_k = R_{k−1} + T·Δ_{k−1}` ([`Transport::apply`]) is what sensing the entries over the
//! cache of `Δ_{k−1}` would measure, in f32 rather than through half-float maps.
//!
//! What the rows leave out: a texture's texel-by-texel albedo on the surfaces seen (a row reads each
//! surface's mean albedo, as the values hold it; the camera's sensors still read the texels).

use glam::Vec3;
use rayon::prelude::*;

use crate::gpu_types::TRANSPORT_NONE;

/// Host memory the rows may take by default: above it the bounces sense the entries again, as before
/// (`GiStats::transport`). A row holds the distinct values a sensor sees, ~100–500 at rd 32 (8 bytes each).
pub const DEFAULT_BUDGET: u64 = 1 << 30;

/// Sparse rows, one per entry, in compressed-row form.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Transport {
    /// Row `i` is `columns[starts[i]..starts[i + 1]]` with `weights` alike: value indices (increasing) and
    /// the weight of each, over π.
    starts: Vec<u32>,
    columns: Vec<u32>,
    weights: Vec<f32>,
}

/// A sensor's row: (value, weight) pairs, increasing by value.
pub type Row = Vec<(u32, f32)>;

/// One sensor's row from its texel list: the distinct values it sees, increasing, each with the sum of its
/// texels' `weights` (already over π); and the weight of the texels that see no surface (the sky's: a
/// constant background `b` sends the sensor `b` times it). `scratch` is reused between calls. Neighbouring
/// texels mostly see one entry, so runs are summed before the sort.
pub fn row(texels: &[u32], weights: &[f32], scratch: &mut Vec<(u32, f32)>) -> (Row, f32) {
    scratch.clear();
    let mut sky = 0.0;
    for (&v, &w) in texels.iter().zip(weights) {
        if w <= 0.0 {
            continue;
        }
        if v == TRANSPORT_NONE {
            sky += w;
            continue;
        }
        match scratch.last_mut() {
            Some(last) if last.0 == v => last.1 += w,
            _ => scratch.push((v, w)),
        }
    }
    scratch.sort_unstable_by_key(|&(v, _)| v);
    let mut out: Vec<(u32, f32)> = Vec::new();
    for &(v, w) in scratch.iter() {
        match out.last_mut() {
            Some(last) if last.0 == v => last.1 += w,
            _ => out.push((v, w)),
        }
    }
    (out, sky)
}

impl Transport {
    /// From one row per entry.
    pub fn from_rows(rows: &[Vec<(u32, f32)>]) -> Self {
        let mut t = Transport { starts: Vec::with_capacity(rows.len() + 1), ..Default::default() };
        t.starts.push(0);
        let nonzeros: usize = rows.iter().map(Vec::len).sum();
        t.columns.reserve(nonzeros);
        t.weights.reserve(nonzeros);
        for r in rows {
            t.columns.extend(r.iter().map(|&(c, _)| c));
            t.weights.extend(r.iter().map(|&(_, w)| w));
            t.starts.push(t.columns.len() as u32);
        }
        t
    }

    /// Rows (entries).
    pub fn rows(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// Weights held in all.
    pub fn nonzeros(&self) -> usize {
        self.columns.len()
    }

    /// Bytes on the host.
    pub fn bytes(&self) -> u64 {
        (4 * self.starts.len() + 8 * self.columns.len()) as u64
    }

    /// The columns and weights of row `i`.
    pub fn row(&self, i: usize) -> impl Iterator<Item = (u32, f32)> + '_ {
        let range = self.starts[i] as usize..self.starts[i + 1] as usize;
        self.columns[range.clone()].iter().copied().zip(self.weights[range].iter().copied())
    }

    /// What `values` (the whole values buffer: entries, then the surface sides' fallbacks) send to each
    /// entry's sensor: `Σ w·values[column]`, R's addition.
    pub fn apply(&self, values: &[Vec3]) -> Vec<Vec3> {
        (0..self.rows()).into_par_iter().map(|i| self.row(i).map(|(c, w)| values[c as usize] * w).sum()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_sums_the_weights_of_each_value_and_the_skys_apart() {
        let texels = [3, TRANSPORT_NONE, 1, 3, 1, 7];
        let weights = [0.5, 9.0, 0.25, 0.125, 1.0, 0.0];
        let r = row(&texels, &weights, &mut Vec::new());
        assert_eq!(r, (vec![(1, 1.25), (3, 0.625)], 9.0));
    }

    #[test]
    fn the_product_is_each_rows_weighted_sum() {
        let t = Transport::from_rows(&[vec![(0, 0.5), (2, 0.25)], vec![], vec![(1, 1.0)]]);
        assert_eq!((t.rows(), t.nonzeros()), (3, 3));
        let v = [Vec3::new(1.0, 2.0, 3.0), Vec3::splat(4.0), Vec3::new(8.0, 0.0, 4.0)];
        assert_eq!(t.apply(&v), vec![Vec3::new(2.5, 1.0, 2.5), Vec3::ZERO, Vec3::splat(4.0)]);
    }
}
