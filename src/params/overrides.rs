//! Values set on the command line or in a scene file's `[render]` table ([`Overrides`], made by the
//! table), read from a scene file and checked: each against its range, then the rules between them.

use std::path::Path;

use serde::Deserialize;

use super::*;

impl Overrides {
    /// The `[render]` table of the scene file `path` (empty when the file has none).
    pub fn from_scene_table(path: &Path, table: &toml::Table) -> anyhow::Result<Self> {
        Self::deserialize(toml::Value::Table(table.clone()))
            .map_err(|e| anyhow::anyhow!("{}: [render]: {}", path.display(), e.message()))
    }

    /// Checks every value that is set against its range, and the values set together (ranges that depend
    /// on the device are checked when the renderer is built); errors carry `origin`.
    pub(super) fn check(&self, origin: &Origin) -> Result<(), ParamError> {
        self.check_each(origin)?;
        if let (Some(e), Some(b)) = (self.epsilon, self.bounces) {
            return Err(ParamError {
                param: Param::Bounces,
                problem: format!(
                    "{b} cannot be combined with {} {e}: ε is the paper's constant in place of reflected light, \
                     bounces compute that light; give one",
                    Param::Epsilon.as_set(origin)
                ),
                origin: Some(origin.clone()),
            });
        }
        Ok(())
    }
}
