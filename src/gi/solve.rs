//! The bounces: the cache after each sensing pass, what changed, and when to stop.
//!
//! Bounce k senses every entry with the cache of bounce k − 1 in the sensor maps (none at bounce 1: direct
//! light only), so the cache after k bounces holds `v_k = Σ_{j<k} Tʲ d`, `d` the direct light reflected
//! once and `T` the transport between entries as the sensors rasterise it (non-negative, the same at every
//! bounce: the sensors are the same). Each bounce adds `Δ_k = T^{k−1} d`, which soon shrinks by a fixed
//! ratio λ, `T`'s dominant eigenvalue (the scene's effective albedo): in a closed box of albedo ρ it is ρ
//! from the first bounce. So the rest of the series is a geometric tail, `Δ_k · λ/(1 − λ)`, added to each
//! entry ([`Solver::values`]): a room of albedo 0.9 needs a few bounces, not the 40 that would leave 1 %.
//!
//! λ is each entry's own: in two rooms joined by a door ajar, the lit room's light settles at its own ratio
//! while the other's, arriving through the gap, settles more slowly; one ratio for all, the lit room's,
//! left the dark room 2.7 % too dark (docs/ACCURACY.md). An entry's ratio is the mean over the last
//! [`RATIO_SPAN`] bounces of what it added; where it added nothing, there is no tail.
//!
//! With `Bounces::Converged` the solver stops when that extrapolated estimate changes between two bounces by
//! less than the tolerance: the area-weighted mean of each entry's relative change (so a dim room counts as
//! much as a bright one); with `Bounces::Fixed(n)` after exactly n bounces, unextrapolated (the oracle's
//! `--bounces n` is the same sum).

use glam::Vec3;

use super::{Entry, MAX_ALBEDO};
use crate::params::Bounces;

/// Relative change of the extrapolated cache below which `auto` stops: a tenth of the accuracy asked of the
/// renders (docs/ACCURACY.md), so that stopping adds no visible error.
pub const DEFAULT_TOLERANCE: f64 = 5e-3;
/// `auto` stops here whatever the change (a scene whose every surface reflects [`MAX_ALBEDO`] needs ~10).
pub const MAX_BOUNCES: u32 = 32;
/// Bounces before the ratio λ is trusted: λ_k compares bounces k and k − 1, and the first bounces still
/// carry the transport's other eigenvectors.
const MIN_EXTRAPOLATED: u32 = 3;

/// Bounces over which λ is measured at most.
const RATIO_SPAN: usize = 3;
/// An entry's λ is at most the scene's and this: a room filling through a door converges more slowly than
/// the scene, but an entry whose additions still grow (light just arriving) is not yet on its tail, and a
/// ratio near 1 there made the estimate swing from bounce to bounce (the room took 15 bounces instead of 8,
/// for the same image).
const RATIO_ABOVE_SCENE: f32 = 0.1;

/// Rec. 709 luminance, the weight of the change (as `compare`).
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

pub struct Solver {
    bounces: Bounces,
    tolerance: f64,
    /// After the last bounce: `v_k` and what that bounce added, `Δ_k`.
    current: Vec<Vec3>,
    added: Vec<Vec3>,
    /// What each bounce added and what the cache then held, in luminance × area: their ratio is the
    /// bounce's relative change, and two bounces' additions the scene's λ (for the statistics).
    changes: Vec<(f64, f64)>,
    /// Each entry's addition (luminance) at the last [`RATIO_SPAN`] + 1 bounces, oldest first: its own λ.
    history: std::collections::VecDeque<Vec<f32>>,
    /// The extrapolated estimate after the previous bounce (for `auto`'s stopping rule).
    previous_estimate: Option<Vec<Vec3>>,
    /// How much the extrapolated estimate moved at the last bounce, relative.
    pub last_change: Option<f64>,
}

/// What a bounce tells the renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    Bounce,
    Done,
}

impl Solver {
    /// `bounces`: at least one (0 bounces need no cache).
    pub fn new(bounces: Bounces, tolerance: f64, entries: usize) -> Self {
        Self {
            bounces,
            tolerance,
            current: vec![Vec3::ZERO; entries],
            added: vec![Vec3::ZERO; entries],
            changes: Vec::new(),
            history: std::collections::VecDeque::new(),
            previous_estimate: None,
            last_change: None,
        }
    }

    /// Bounces done.
    pub fn bounces(&self) -> u32 {
        self.changes.len() as u32
    }

    /// The cache after bounce k from `r`, R sensed at each entry over the cache of bounce k − 1: its
    /// reflected radiance `Kd·R` (`albedo` per entry), and whether to sense another bounce.
    pub fn step(&mut self, entries: &[Entry], albedo: &[Vec3], r: &[Vec3]) -> Next {
        let (mut moved, mut total) = (0.0f64, 0.0f64);
        for (i, ((e, kd), r)) in entries.iter().zip(albedo).zip(r).enumerate() {
            let v = *kd * r.max(Vec3::ZERO);
            self.added[i] = v - self.current[i];
            self.current[i] = v;
            moved += (self.added[i].abs().dot(LUMINANCE) * e.area) as f64;
            total += (v.dot(LUMINANCE) * e.area) as f64;
        }
        self.changes.push((moved, total));
        if self.history.len() > RATIO_SPAN {
            self.history.pop_front();
        }
        self.history.push_back(self.added.iter().map(|d| d.dot(LUMINANCE)).collect());
        let k = self.bounces();
        match self.bounces {
            Bounces::Fixed(n) => {
                self.last_change =
                    self.changes.last().map(|&(moved, total)| if total > 0.0 { moved / total } else { 0.0 });
                if k >= n { Next::Done } else { Next::Bounce }
            }
            Bounces::Converged => {
                let estimate = self.values();
                if let Some(previous) = &self.previous_estimate {
                    self.last_change = Some(relative_change(entries, &estimate, previous));
                }
                self.previous_estimate = Some(estimate);
                let settled = self.last_change.is_some_and(|c| c < self.tolerance) && k >= MIN_EXTRAPOLATED;
                if settled || self.changes[k as usize - 1].0 == 0.0 || k >= MAX_BOUNCES {
                    Next::Done
                } else {
                    Next::Bounce
                }
            }
        }
    }

    /// What the last bounce added to the cache, `Δ_k`: what the next bounce transports.
    pub fn added(&self) -> &[Vec3] {
        &self.added
    }

    /// λ, the ratio by which the bounces shrink, once it can be trusted (`auto` only): the mean ratio over
    /// the last [`RATIO_SPAN`] bounces but the first. One bounce's addition is a difference of half-float
    /// maps: its ratio to the last wanders by a few 1e-4, which the tail multiplies by `1/(1 − λ)²` (100 at
    /// λ = 0.9); over three bounces it wanders a third as much.
    pub fn ratio(&self) -> Option<f64> {
        let k = self.changes.len();
        if self.bounces != Bounces::Converged || k < MIN_EXTRAPOLATED as usize {
            return None;
        }
        let span = (k - 2).min(RATIO_SPAN);
        let (last, first) = (self.changes[k - 1].0, self.changes[k - 1 - span].0);
        if first <= 0.0 {
            return None;
        }
        Some((last / first).powf(1.0 / span as f64).clamp(0.0, MAX_ALBEDO as f64))
    }

    /// Entry `i`'s λ: the mean ratio of its additions over the bounces [`Solver::ratio`] uses (0 where it
    /// added nothing then), at most [`RATIO_ABOVE_SCENE`] above the scene's.
    fn entry_ratio(&self, i: usize) -> f32 {
        let k = self.history.len();
        let span = (self.changes.len() - 2).min(RATIO_SPAN).min(k - 1);
        let (first, last) = (self.history[k - 1 - span][i], self.history[k - 1][i]);
        if first <= 0.0 || last <= 0.0 {
            return 0.0;
        }
        let scene = self.ratio().unwrap_or(0.0) as f32;
        (last / first).powf(1.0 / span as f32).clamp(0.0, MAX_ALBEDO.min(scene + RATIO_ABOVE_SCENE))
    }

    /// The cache to gather from: after the last bounce, with `auto` each entry's geometric tail added.
    pub fn values(&self) -> Vec<Vec3> {
        if self.ratio().is_none() {
            return self.current.clone();
        }
        (self.current.iter().zip(&self.added).enumerate())
            .map(|(i, (v, d))| {
                let lambda = self.entry_ratio(i);
                *v + d.max(Vec3::ZERO) * (lambda / (1.0 - lambda))
            })
            .collect()
    }

    /// The share of the cache's light the tail adds (0 without extrapolation), at the scene's λ.
    pub fn tail_share(&self) -> f64 {
        let Some(lambda) = self.ratio() else { return 0.0 };
        let (added, total) = self.changes[self.changes.len() - 1];
        let tail = added * lambda / (1.0 - lambda);
        if total + tail > 0.0 { tail / (total + tail) } else { 0.0 }
    }
}

/// The area-weighted mean relative change of each entry's luminance from `before` to `after`, an entry's
/// change relative to its luminance, at least a hundredth of the cache's mean (so that the darkest entries,
/// whose relative change is noise, do not decide).
fn relative_change(entries: &[Entry], after: &[Vec3], before: &[Vec3]) -> f64 {
    let area: f64 = entries.iter().map(|e| e.area as f64).sum();
    if area <= 0.0 {
        return 0.0;
    }
    let mean = entries.iter().zip(after).map(|(e, v)| (v.dot(LUMINANCE) * e.area) as f64).sum::<f64>() / area;
    let floor = (1e-2 * mean).max(f64::MIN_POSITIVE);
    let weighted: f64 = (entries.iter().zip(after).zip(before))
        .map(|((e, a), b)| {
            e.area as f64 * ((*a - *b).dot(LUMINANCE).abs() as f64 / (a.dot(LUMINANCE) as f64).max(floor))
        })
        .sum();
    weighted / area
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(n: usize) -> Vec<Entry> {
        (0..n).map(|_| Entry { point: Vec3::ZERO, normal: Vec3::Y, surface: 1, front: true, area: 1.0 }).collect()
    }

    /// A closed box of albedo ρ lit by its own uniform emission `E` (reflected once: ρE): bounce k senses
    /// `R_k = E + v_{k−1}/ρ·ρ` … i.e. `v_k = ρE·(1 + ρ + … + ρ^{k−1})`, converging to `ρE/(1 − ρ)`. The tail
    /// makes the third bounce exact.
    #[test]
    fn a_geometric_series_is_summed_from_three_bounces() {
        let (rho, e) = (0.9f32, 2.0f32);
        let n = 4;
        let (es, kd) = (entries(n), vec![Vec3::splat(rho); n]);
        let mut s = Solver::new(Bounces::Converged, DEFAULT_TOLERANCE, n);
        let mut values = vec![Vec3::ZERO; n];
        let mut steps = 0;
        loop {
            // R at an entry: the emission arriving plus what the other walls reflect.
            let r: Vec<Vec3> = values.iter().map(|v| Vec3::splat(e) + *v).collect();
            steps += 1;
            let next = s.step(&es, &kd, &r);
            values = s.current.clone();
            if next == Next::Done {
                break;
            }
        }
        let exact = rho * e / (1.0 - rho);
        let got = s.values()[0].x;
        assert!(((got - exact) / exact).abs() < 1e-4, "{got} against {exact}");
        assert!(steps <= 4, "{steps} bounces for ρ = 0.9");
        assert!((s.ratio().unwrap() - rho as f64).abs() < 1e-5);
        assert!(s.tail_share() > 0.5, "most of ρ = 0.9's light is in the tail: {}", s.tail_share());
    }

    /// Two groups of entries whose additions shrink at their own ratios (a room lit through a door ajar
    /// beside the lit room): each gets its own tail; one ratio for all would leave the slow group short.
    #[test]
    fn each_entry_extrapolates_at_its_own_ratio() {
        let n = 4;
        let (es, kd) = (entries(n), vec![Vec3::ONE; n]);
        let ratios = [0.5f32, 0.5, 0.8, 0.8];
        let mut s = Solver::new(Bounces::Converged, 1e-6, n);
        // R_k at entry i: the partial sum of a geometric series of ratio ratios[i], first term 1.
        let mut k = 0;
        loop {
            k += 1;
            let r: Vec<Vec3> = ratios.iter().map(|&q| Vec3::splat((1.0 - q.powi(k)) / (1.0 - q))).collect();
            if s.step(&es, &kd, &r) == Next::Done {
                break;
            }
        }
        for (v, q) in s.values().iter().zip(ratios) {
            let exact = 1.0 / (1.0 - q);
            assert!(((v.x - exact) / exact).abs() < 1e-3, "ratio {q}: {} against {exact} after {k} bounces", v.x);
        }
    }

    #[test]
    fn a_fixed_count_is_not_extrapolated() {
        let n = 2;
        let (es, kd) = (entries(n), vec![Vec3::splat(0.5); n]);
        let mut s = Solver::new(Bounces::Fixed(2), DEFAULT_TOLERANCE, n);
        assert_eq!(s.step(&es, &kd, &vec![Vec3::ONE; n]), Next::Bounce);
        assert_eq!(s.step(&es, &kd, &vec![Vec3::splat(1.5); n]), Next::Done);
        assert_eq!(s.values(), vec![Vec3::splat(0.75); n]);
        assert_eq!(s.ratio(), None);
    }

    #[test]
    fn darkness_stops_at_once() {
        let n = 3;
        let mut s = Solver::new(Bounces::Converged, DEFAULT_TOLERANCE, n);
        assert_eq!(s.step(&entries(n), &vec![Vec3::splat(0.5); n], &vec![Vec3::ZERO; n]), Next::Done);
        assert_eq!(s.values(), vec![Vec3::ZERO; n]);
    }
}
