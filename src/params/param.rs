//! Where a parameter's value came from, and the error that names a bad value as the user wrote it.

use std::fmt;
use std::path::PathBuf;

use super::Param;

impl Param {
    /// The parameter as the user set it: the flag, or the scene file's `[render]` key.
    pub fn as_set(self, origin: &Origin) -> String {
        match origin {
            Origin::SceneFile(path) => format!("{}: [render] {}", path.display(), self.key()),
            _ => self.flag().to_owned(),
        }
    }
}

/// Where a parameter's value came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    Flag,
    SceneFile(PathBuf),
    Default,
}

/// A parameter value out of its range, named as the user wrote it (once [`ParamError::origin`] is known).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub struct ParamError {
    pub param: Param,
    /// What is wrong, as a predicate: "must be a power of two (1, 2, 4, …), got 12".
    pub problem: String,
    /// `None` where the code that found the problem cannot know (e.g. a device limit checked by the
    /// renderer): [`RenderParams::attribute`] fills it in.
    pub origin: Option<Origin>,
}

impl ParamError {
    pub fn new(param: Param, problem: impl Into<String>) -> Self {
        Self { param, problem: problem.into(), origin: None }
    }
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let origin = self.origin.clone().unwrap_or(Origin::Flag);
        write!(f, "{} {}", self.param.as_set(&origin), self.problem)
    }
}
