//! Self-check results and choices already made, kept in a JSON file per user, keyed by device, driver and
//! build (a new driver or new shaders invalidate them).

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context as _, Result};
use serde::{Deserialize, Serialize};

use super::{CheckResult, StrategyKind};
use crate::output::atomic;
use crate::params::EstimatorKind;
use crate::sensors::SensorKind;
use crate::vk::Adapter;

#[derive(Default, Serialize, Deserialize)]
pub struct Cache {
    #[serde(skip)]
    path: Option<PathBuf>,
    checks: BTreeMap<String, CheckResult>,
    choices: BTreeMap<String, StrategyKind>,
    /// Whether a mesh's sensor maps are drawn from its clusters, as measured (`renderer::detail`).
    #[serde(default)]
    cluster_choices: BTreeMap<String, bool>,
}

impl Cache {
    /// The cache in `$SENSORLIGHT_CACHE_DIR`, else `$XDG_CACHE_HOME/sensorlight`, else `~/.cache/sensorlight`.
    /// A missing or unreadable file is an empty cache.
    pub fn open_default() -> Self {
        let dir = std::env::var_os("SENSORLIGHT_CACHE_DIR").map(PathBuf::from).or_else(|| {
            std::env::var_os("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
                .map(|d| d.join("sensorlight"))
        });
        let Some(dir) = dir else { return Self::default() };
        let path = dir.join("strategies.json");
        let mut cache: Self =
            std::fs::read(&path).ok().and_then(|bytes| serde_json::from_slice(&bytes).ok()).unwrap_or_default();
        cache.path = Some(path);
        cache
    }

    /// A cache that is not saved (tests, benchmarks that must measure afresh).
    pub fn in_memory() -> Self {
        Self::default()
    }

    pub(super) fn check(
        &self,
        device: &str,
        sensor: SensorKind,
        estimator: EstimatorKind,
        strategy: StrategyKind,
    ) -> Option<CheckResult> {
        self.checks.get(&check_key(device, sensor, estimator, strategy)).copied()
    }

    /// Records a self-check result as if it had been run (e.g. to test that `auto` honours a failure).
    pub fn record_check(
        &mut self,
        device: &str,
        sensor: SensorKind,
        estimator: EstimatorKind,
        strategy: StrategyKind,
        result: CheckResult,
    ) {
        self.checks.insert(check_key(device, sensor, estimator, strategy), result);
    }

    pub(super) fn choice(&self, key: &str) -> Option<StrategyKind> {
        self.choices.get(key).copied()
    }

    pub(super) fn record_choice(&mut self, key: String, strategy: StrategyKind) {
        self.choices.insert(key, strategy);
    }

    /// Whether the clusters measured faster for what `key` names (`renderer::detail`), if measured.
    pub fn cluster_choice(&self, key: &str) -> Option<bool> {
        self.cluster_choices.get(key).copied()
    }

    pub fn record_cluster_choice(&mut self, key: String, clusters: bool) {
        self.cluster_choices.insert(key, clusters);
    }

    pub fn save(&self) -> Result<()> {
        let Some(path) = &self.path else { return Ok(()) };
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        atomic::write_bytes(path, &serde_json::to_vec_pretty(self)?)
    }
}

/// Identifies a device, its driver and this build: a new driver or new shaders invalidate what was cached.
pub fn device_key(adapter: &Adapter) -> String {
    // FNV-1a over every shader's SPIR-V.
    let shaders = crate::shaders::ALL
        .iter()
        .flat_map(|(_, spirv)| spirv.iter())
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3));
    format!("{} | {} | {} {:016x}", adapter.name, adapter.driver, env!("CARGO_PKG_VERSION"), shaders)
}

fn check_key(device: &str, sensor: SensorKind, estimator: EstimatorKind, strategy: StrategyKind) -> String {
    format!("{device} | {sensor} | {estimator} | {strategy}")
}
