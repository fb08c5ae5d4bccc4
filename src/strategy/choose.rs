//! The self-check and the choice of a strategy, on measurements a [`Prober`] makes.

use std::time::Duration;

use anyhow::{Result, bail};
use glam::Vec4;

use super::{CHECK_BATCH, CHECK_RD, CHECK_SENSORS, Cache, CheckResult, StrategyKind, StrategyRequest, measure_sensors};
use crate::params::EstimatorKind;
use crate::sensors::SensorKind;

/// Renders the probe for the strategy module: implemented by the renderer.
pub trait Prober {
    /// The device's name, for messages.
    fn device_name(&self) -> String;
    /// The cache key of the device, driver and build (see [`super::device_key`]).
    fn device_key(&self) -> String;
    /// Why `kind` cannot run here with sensor maps of `rd`, if it cannot.
    fn unsupported(&self, kind: StrategyKind, rd: u32) -> Option<String>;
    /// R at the first `sensors` probe sensors, sensed by `kind` with maps of `rd` in batches of at most
    /// `batch` sensors (`None`: as many as the memory budget allows), and the host time sensing took.
    fn probe(
        &mut self,
        kind: StrategyKind,
        rd: u32,
        sensors: usize,
        batch: Option<u32>,
    ) -> Result<(Vec<Vec4>, Duration)>;
}

/// What the choice did, for whoever reports it.
#[derive(Clone, Debug)]
pub enum Event {
    /// A self-check ran now, or its result came from the cache.
    Checked { strategy: StrategyKind, result: CheckResult, cached: bool },
    /// The strategy cannot run on this device at this size.
    Unsupported { strategy: StrategyKind, why: String },
    /// `auto` measured these per-sensor times at the requested size.
    Measured { rd: u32, per_sensor: Vec<(StrategyKind, Duration)> },
}

/// The strategy chosen, and how.
#[derive(Clone, Debug)]
pub struct Choice {
    pub strategy: StrategyKind,
    pub reason: String,
}

/// Checks `strategy` against `per-sensor` on the probe.
pub fn self_check(prober: &mut dyn Prober, strategy: StrategyKind) -> Result<CheckResult> {
    let batch = Some(CHECK_BATCH);
    let (reference, _) = prober.probe(StrategyKind::PerSensor, CHECK_RD, CHECK_SENSORS, batch)?;
    let (r, _) = prober.probe(strategy, CHECK_RD, CHECK_SENSORS, batch)?;
    Ok(CheckResult::judge(&r, &reference))
}

/// The strategy to use for `sensor` sensors of size `rd` read by `estimator`, with `budget` bytes per batch:
/// the requested one if it passes its self-check, else (auto) the fastest strategy whose R is per-sensor's
/// bit for bit (it rasterizes as per-sensor does, and is identical on the probe), measured at `rd`. The prober renders with the same sensor and estimator.
#[allow(clippy::too_many_arguments)]
pub fn choose(
    prober: &mut dyn Prober,
    sensor: SensorKind,
    estimator: EstimatorKind,
    rd: u32,
    budget: u64,
    request: StrategyRequest,
    cache: &mut Cache,
    events: &mut dyn FnMut(Event),
) -> Result<Choice> {
    let device = prober.device_key();
    if let StrategyRequest::Fixed(strategy) = request {
        if let Some(why) = prober.unsupported(strategy, rd) {
            bail!("strategy {strategy} cannot run on {}: {why}", prober.device_name());
        }
        let result = checked(prober, (sensor, estimator), strategy, cache, events)?;
        if !result.passed {
            bail!(
                "strategy {strategy} disagrees with per-sensor on {} (max difference {:.2e} of the brightest R); \
                 choose another or auto",
                prober.device_name(),
                result.max_difference
            );
        }
        return Ok(Choice { strategy, reason: "requested".into() });
    }

    let choice_key = format!("{device} | {sensor} | {estimator} | rd {rd} | budget {budget}");
    // A choice made for a scene whose sensors had fewer layers (fewer light groups) may not run on this
    // one's (multiview's view count): then it is measured again.
    if let Some(strategy) = cache.choice(&choice_key).filter(|&s| prober.unsupported(s, rd).is_none()) {
        return Ok(Choice { strategy, reason: "auto: fastest correct strategy here, cached".into() });
    }
    let mut candidates = Vec::new();
    for strategy in StrategyKind::ALL {
        if let Some(why) = prober.unsupported(strategy, rd) {
            events(Event::Unsupported { strategy, why });
        } else if checked(prober, (sensor, estimator), strategy, cache, events)?.identical
            && strategy.rasterizes_like_per_sensor()
        {
            candidates.push(strategy);
        }
    }
    let sensors = measure_sensors(rd);
    for &strategy in &candidates {
        prober.probe(strategy, rd, sensors, None)?; // warm-up: pipelines compile lazily
    }
    let mut best = vec![Duration::MAX; candidates.len()];
    for _round in 0..2 {
        for (i, &strategy) in candidates.iter().enumerate() {
            let (r, time) = prober.probe(strategy, rd, sensors, None)?;
            best[i] = best[i].min(time / r.len().max(1) as u32);
        }
    }
    let Some((index, _)) = best.iter().enumerate().min_by_key(|(_, t)| **t) else {
        bail!("no sensor-map strategy runs correctly on {}", prober.device_name());
    };
    events(Event::Measured { rd, per_sensor: candidates.iter().copied().zip(best.iter().copied()).collect() });
    let strategy = candidates[index];
    cache.record_choice(choice_key, strategy);
    cache.save()?;
    Ok(Choice { strategy, reason: "auto: fastest correct strategy here, measured".into() })
}

/// `strategy`'s self-check result: from the cache, else run now and cached.
fn checked(
    prober: &mut dyn Prober,
    (sensor, estimator): (SensorKind, EstimatorKind),
    strategy: StrategyKind,
    cache: &mut Cache,
    events: &mut dyn FnMut(Event),
) -> Result<CheckResult> {
    let device = prober.device_key();
    if let Some(result) = cache.check(&device, sensor, estimator, strategy) {
        events(Event::Checked { strategy, result, cached: true });
        return Ok(result);
    }
    let result = self_check(prober, strategy)?;
    events(Event::Checked { strategy, result, cached: false });
    cache.record_check(&device, sensor, estimator, strategy, result);
    cache.save()?;
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A prober whose strategies return per-sensor's R plus an error, and take fixed times.
    struct Fake {
        error: fn(StrategyKind) -> f32,
        time: fn(StrategyKind) -> u64,
        probes: Vec<(StrategyKind, u32, Option<u32>)>,
    }

    impl Prober for Fake {
        fn device_name(&self) -> String {
            "fake".into()
        }
        fn device_key(&self) -> String {
            "fake device".into()
        }
        fn unsupported(&self, kind: StrategyKind, _rd: u32) -> Option<String> {
            (kind == StrategyKind::Multiview).then(|| "no multiview".into())
        }
        fn probe(
            &mut self,
            kind: StrategyKind,
            rd: u32,
            sensors: usize,
            batch: Option<u32>,
        ) -> Result<(Vec<Vec4>, Duration)> {
            self.probes.push((kind, rd, batch));
            let r = (0..sensors).map(|i| Vec4::splat(1.0 + i as f32 + (self.error)(kind))).collect();
            Ok((r, Duration::from_micros((self.time)(kind) * sensors as u64)))
        }
    }

    /// `request` chosen for hemicube sensors of rd 64 with the exact estimator and a 1 MiB budget.
    fn choose_with(
        fake: &mut Fake,
        request: StrategyRequest,
        cache: &mut Cache,
        events: &mut dyn FnMut(Event),
    ) -> Result<Choice> {
        choose(fake, SensorKind::Hemicube, EstimatorKind::Exact, 64, 1 << 20, request, cache, events)
    }

    #[test]
    fn auto_takes_the_fastest_strategy_that_passes_and_caches_both() {
        // Atlas is fastest but wrong; layered is the fastest correct one.
        let mut fake = Fake {
            error: |k| if k == StrategyKind::Atlas { 0.5 } else { 0.0 },
            time: |k| match k {
                StrategyKind::Atlas => 1,
                StrategyKind::Layered => 2,
                _ => 10,
            },
            probes: Vec::new(),
        };
        let (mut cache, mut events) = (Cache::in_memory(), Vec::new());
        let choice = choose_with(&mut fake, StrategyRequest::Auto, &mut cache, &mut |e| events.push(e)).unwrap();
        assert_eq!(choice.strategy, StrategyKind::Layered);
        assert!(events.iter().any(|e| matches!(e, Event::Unsupported { strategy: StrategyKind::Multiview, .. })));
        assert!(
            events
                .iter()
                .any(|e| matches!(e, Event::Checked { strategy: StrategyKind::Atlas, result, .. } if !result.passed))
        );
        assert!(fake.probes.contains(&(StrategyKind::Atlas, CHECK_RD, Some(CHECK_BATCH))), "checked on the probe");
        // A second choice comes from the cache: nothing is rendered.
        fake.probes.clear();
        let again = choose_with(&mut fake, StrategyRequest::Auto, &mut cache, &mut |_| ()).unwrap();
        assert_eq!(again.strategy, StrategyKind::Layered);
        assert!(fake.probes.is_empty(), "{:?}", fake.probes);
        // A named strategy that failed its (cached) check is refused with the reason.
        let err = choose_with(&mut fake, StrategyRequest::Fixed(StrategyKind::Atlas), &mut cache, &mut |_| ())
            .unwrap_err()
            .to_string();
        assert!(err.contains("disagrees with per-sensor"), "{err}");
        let err = choose_with(&mut fake, StrategyRequest::Fixed(StrategyKind::Multiview), &mut cache, &mut |_| ())
            .unwrap_err()
            .to_string();
        assert!(err.contains("cannot run") && err.contains("no multiview"), "{err}");
    }

    /// A strategy whose R differs from per-sensor's only in the last bits on the probe (layered here), or
    /// that rasterizes at offsets (the atlas), passes its check and runs when named, but `auto` does not take
    /// it, however fast: the image must not depend on a timing.
    #[test]
    fn auto_takes_only_strategies_identical_to_per_sensor() {
        let mut fake = Fake {
            error: |k| if k == StrategyKind::Layered { 1e-6 } else { 0.0 },
            time: |k| match k {
                StrategyKind::Layered => 1,
                StrategyKind::Atlas => 2,
                _ => 10,
            },
            probes: Vec::new(),
        };
        let mut cache = Cache::in_memory();
        let auto = choose_with(&mut fake, StrategyRequest::Auto, &mut cache, &mut |_| ()).unwrap();
        assert!(![StrategyKind::Layered, StrategyKind::Atlas].contains(&auto.strategy), "{auto:?}");
        for kind in [StrategyKind::Layered, StrategyKind::Atlas] {
            let named = choose_with(&mut fake, StrategyRequest::Fixed(kind), &mut cache, &mut |_| ());
            assert_eq!(named.unwrap().strategy, kind);
        }
    }

    /// A cached choice that cannot run here (multiview chosen for sensors of few layers, met by sensors of
    /// more than its view count) is measured again, not used.
    #[test]
    fn a_cached_choice_that_cannot_run_is_chosen_again() {
        let mut fake =
            Fake { error: |_| 0.0, time: |k| if k == StrategyKind::Layered { 1 } else { 10 }, probes: Vec::new() };
        let mut cache = Cache::in_memory();
        let key =
            format!("fake device | {} | {} | rd 64 | budget {}", SensorKind::Hemicube, EstimatorKind::Exact, 1 << 20);
        cache.record_choice(key, StrategyKind::Multiview);
        let choice = choose_with(&mut fake, StrategyRequest::Auto, &mut cache, &mut |_| ()).unwrap();
        assert_eq!(choice.strategy, StrategyKind::Layered);
        assert!(!fake.probes.is_empty(), "measured again");
    }
}
