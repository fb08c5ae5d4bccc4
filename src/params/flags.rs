//! The parameters as command-line flags: how each type is read and shown, and [`ParamFlags`], the set of
//! flags a sub-command takes, made from the table (so `--help`, the parsing and the scene file agree).

use std::marker::PhantomData;

use clap::builder::{EnumValueParser, ValueParser};

use super::{Antialiasing, Bounces, EstimatorKind, Overrides, Param, SensorShape};

/// A parameter's type as a flag: how it is parsed and how its default is shown.
pub trait FlagValue: Clone + Send + Sync + 'static {
    fn parser() -> ValueParser;
    fn show(&self) -> String;
}

impl FlagValue for u32 {
    fn parser() -> ValueParser {
        ValueParser::new(whole)
    }
    fn show(&self) -> String {
        self.to_string()
    }
}

impl FlagValue for f32 {
    fn parser() -> ValueParser {
        clap::value_parser!(f32).into()
    }
    fn show(&self) -> String {
        self.to_string()
    }
}

impl FlagValue for [f32; 3] {
    fn parser() -> ValueParser {
        ValueParser::new(parse_rgb)
    }
    fn show(&self) -> String {
        format!("{},{},{}", self[0], self[1], self[2])
    }
}

impl FlagValue for Bounces {
    fn parser() -> ValueParser {
        ValueParser::new(|text: &str| text.parse::<Bounces>())
    }
    fn show(&self) -> String {
        self.to_string()
    }
}

macro_rules! choice {
    ($($t:ty),*) => {$(
        impl FlagValue for $t {
            fn parser() -> ValueParser {
                EnumValueParser::<$t>::new().into()
            }
            fn show(&self) -> String {
                self.to_string()
            }
        }
    )*};
}
choice!(EstimatorKind, SensorShape, Antialiasing);

/// The parameters a sub-command takes as flags.
pub trait FlagSet {
    const PARAMS: &'static [Param];
}

/// The flags of the parameters in `S`, as a clap argument group to `#[command(flatten)]`.
#[derive(Clone, Debug, Default)]
pub struct ParamFlags<S> {
    /// What the flags set; the others `None`.
    pub values: Overrides,
    set: PhantomData<S>,
}

impl<S: FlagSet> clap::FromArgMatches for ParamFlags<S> {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut flags = Self { values: Overrides::default(), set: PhantomData };
        flags.update_from_arg_matches(matches)?;
        Ok(flags)
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        S::PARAMS.iter().for_each(|&param| self.values.read(param, matches));
        Ok(())
    }
}

impl<S: FlagSet> clap::Args for ParamFlags<S> {
    fn augment_args(command: clap::Command) -> clap::Command {
        S::PARAMS.iter().fold(command, |command, param| command.arg(param.arg()))
    }

    fn augment_args_for_update(command: clap::Command) -> clap::Command {
        Self::augment_args(command)
    }
}

/// R,G,B, or one value for grey.
pub fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let values: Result<Vec<f32>, _> = parts.iter().map(|p| p.trim().parse::<f32>()).collect();
    match values {
        Ok(v) if v.len() == 3 => Ok([v[0], v[1], v[2]]),
        Ok(v) if v.len() == 1 => Ok([v[0]; 3]),
        _ => Err(format!("expected R,G,B (or one value for grey), got '{s}'")),
    }
}

/// A whole number for a count or size flag: a negative one is said as such, not as clap's tip to pass it
/// after `--`.
pub fn whole(text: &str) -> Result<u32, String> {
    match text.trim().parse::<i64>() {
        Ok(n) if n < 0 => Err(format!("{n} is negative; a whole number of 0 or more is expected")),
        Ok(n) => u32::try_from(n).map_err(|_| format!("{n} is too large (at most {})", u32::MAX)),
        Err(_) => Err(format!("'{text}' is not a whole number")),
    }
}

#[cfg(test)]
mod tests {
    use clap::{Args, FromArgMatches};

    use super::*;
    use crate::params::{Origin, RenderParams};

    enum All {}

    impl FlagSet for All {
        const PARAMS: &'static [Param] = Param::ALL;
    }

    /// Each entry of the table becomes a flag that sets its own value (not a neighbour's, not the default),
    /// said to come from the flag, with its default in its help.
    #[test]
    fn every_parameter_is_a_flag_that_sets_its_value() {
        let defaults = RenderParams::resolve(None, &Overrides::default()).unwrap().values;
        for &param in Param::ALL {
            let command = ParamFlags::<All>::augment_args(clap::Command::new("t"));
            let arg = param.arg();
            // A value unlike every default: an enum's last choice, else 2.
            let choices = arg.get_possible_values();
            let value = choices.last().map_or("2".to_owned(), |c| c.get_name().to_owned());
            let matches = command.try_get_matches_from(["t", param.flag(), &value]).unwrap();
            let flags = ParamFlags::<All>::from_arg_matches(&matches).unwrap();
            let resolved = RenderParams::resolve(None, &flags.values).unwrap();
            assert_eq!(resolved.origin(param), Origin::Flag, "{param:?}");
            assert_ne!(resolved.values, defaults, "{} {value} changed nothing", param.flag());
            let mut one = Overrides::default();
            one.read(param, &matches);
            assert_eq!(format!("{one:?}").matches("Some(").count(), 1, "{param:?} sets one value: {one:?}");
            assert!(param.help().contains("[default: "), "{}", param.help());
            assert!(param.flag().starts_with("--") && !param.key().contains('-'));
        }
    }
}
