//! The machinery behind the parameter table (`table.rs`): from one entry per parameter — its flag, its
//! scene-file key, its type, default, check and help — the `parameters!` macro writes [`Param`], the
//! [`Overrides`] a flag or a scene file sets, the resolved [`Values`], and the command-line arguments.
//!
//! [`Param`]: super::Param
//! [`Overrides`]: super::Overrides
//! [`Values`]: super::Values

use super::{EstimatorKind, flags::FlagValue};

/// A parameter's default: one value, or one per estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fallback<T> {
    Value(T),
    ByEstimator(EstimatorDefault<T>),
}

impl<T: Copy> Fallback<T> {
    pub fn value(&self, kind: EstimatorKind) -> T {
        match self {
            Self::Value(v) => *v,
            Self::ByEstimator(d) => d.for_estimator(kind),
        }
    }
}

impl<T: FlagValue> Fallback<T> {
    /// The default as `--help` shows it.
    pub fn show(&self) -> String {
        match self {
            Self::Value(v) => v.show(),
            Self::ByEstimator(d) => format!("{} (paper's estimator: {})", d.exact.show(), d.paper.show()),
        }
    }
}

/// A default that depends on the estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorDefault<T> {
    pub exact: T,
    pub paper: T,
}

impl<T: Copy> EstimatorDefault<T> {
    pub fn for_estimator(&self, kind: EstimatorKind) -> T {
        match kind {
            EstimatorKind::Exact => self.exact,
            EstimatorKind::Paper => self.paper,
        }
    }
}

/// A check that accepts every value.
pub fn any<T>(_: &T) -> Result<(), String> {
    Ok(())
}

/// Writes, from the table's entries, everything a parameter needs; see `table.rs` for the entries' fields.
macro_rules! parameters {
    ($(
        $(#[doc = $doc:literal])*
        $name:ident: $ty:ty {
            flag: $flag:literal,
            key: $key:ident,
            value_name: $value_name:literal,
            default: $default:expr,
            $(shown: $shown:literal,)?
            check: $check:expr,
            help: $help:expr $(,)?
        }
    ),* $(,)?) => {
        /// A user-settable parameter: one entry of the table.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum Param {
            $($(#[doc = $doc])* $name,)*
        }

        impl Param {
            /// Every parameter, in the table's order.
            pub const ALL: &'static [Param] = &[$(Param::$name),*];

            /// The command-line flag (`--tile`).
            pub fn flag(self) -> &'static str {
                match self { $(Self::$name => $flag,)* }
            }

            /// The key in a scene file's `[render]` table (`tile`); also the argument's id.
            pub fn key(self) -> &'static str {
                match self { $(Self::$name => stringify!($key),)* }
            }

            /// What `--help` says of it, its default included.
            pub fn help(self) -> String {
                match self {
                    $(Self::$name => {
                        let shown: Option<&str> = None $(.or(Some($shown)))?;
                        let default: $crate::params::declare::Fallback<$ty> = $default;
                        let shown = shown.map_or_else(|| default.show(), str::to_owned);
                        format!("{} [default: {shown}]", String::from($help))
                    })*
                }
            }

            /// The command-line argument.
            pub fn arg(self) -> clap::Arg {
                let parser = match self {
                    $(Self::$name => <$ty as $crate::params::flags::FlagValue>::parser(),)*
                };
                let value_name = match self { $(Self::$name => $value_name,)* };
                clap::Arg::new(self.key())
                    .long(&self.flag()[2..])
                    .value_name(value_name)
                    .help(self.help())
                    .value_parser(parser)
                    .allow_negative_numbers(true)
            }
        }

        /// Values set on the command line or in a scene file's `[render]` table; `None` falls back (flag →
        /// scene → default). The field names are the `[render]` keys.
        #[derive(Clone, Debug, Default, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct Overrides {
            $($(#[doc = $doc])* pub $key: Option<$ty>,)*
        }

        impl Overrides {
            /// Each value that is set, against its own range; errors carry `origin`.
            pub(super) fn check_each(&self, origin: &Origin) -> Result<(), ParamError> {
                $(
                    if let Some(value) = &self.$key {
                        let check: fn(&$ty) -> Result<(), String> = $check;
                        check(value).map_err(|problem| ParamError {
                            param: Param::$name,
                            problem,
                            origin: Some(origin.clone()),
                        })?;
                    }
                )*
                Ok(())
            }

            /// The flags that set these values, as a command line takes them (`--tile 8`): to pass them on.
            pub fn to_args(&self) -> Vec<String> {
                let mut args = Vec::new();
                $(
                    if let Some(value) = &self.$key {
                        args.push($flag.to_owned());
                        args.push($crate::params::flags::FlagValue::show(value));
                    }
                )*
                args
            }

            /// Sets `param` from the command line's `matches`, where it was given.
            pub fn read(&mut self, param: Param, matches: &clap::ArgMatches) {
                match param {
                    $(Param::$name => self.$key = matches.get_one::<$ty>(param.key()).cloned(),)*
                }
            }
        }

        /// Every parameter's value: the flag's, else the scene file's, else the table's default.
        #[derive(Clone, Debug, PartialEq)]
        pub struct Values {
            $($(#[doc = $doc])* pub $key: $ty,)*
        }

        impl Values {
            /// `param`'s value as its flag takes it.
            pub fn show(&self, param: Param) -> String {
                match param {
                    $(Param::$name => $crate::params::flags::FlagValue::show(&self.$key),)*
                }
            }

            /// `flags` over `scene` (from `scene_origin`) over the defaults for the estimator `kind`,
            /// recording in `origins` where each value that was set came from.
            pub(super) fn resolve(
                flags: &Overrides,
                scene: &Overrides,
                scene_origin: &Origin,
                kind: EstimatorKind,
                origins: &mut std::collections::BTreeMap<Param, Origin>,
            ) -> Self {
                Self {
                    $($key: {
                        if flags.$key.is_some() {
                            origins.insert(Param::$name, Origin::Flag);
                        } else if scene.$key.is_some() {
                            origins.insert(Param::$name, scene_origin.clone());
                        }
                        let default: $crate::params::declare::Fallback<$ty> = $default;
                        flags.$key.clone().or_else(|| scene.$key.clone()).unwrap_or_else(|| default.value(kind))
                    },)*
                }
            }
        }
    };
}
