//! Argument pieces shared by subcommands: a library enum read by its one parser, `NAME=VALUE` settings.

use anyhow::{Result, bail};
use clap::builder::{PossibleValue, TypedValueParser};
use std::ffi::OsStr;
use std::marker::PhantomData;
use std::str::FromStr;

/// Reads a library enum through its `FromStr` (whose error names the valid names), its names listed in `--help`.
#[derive(Clone)]
pub struct OneOf<T> {
    names: Vec<&'static str>,
    value: PhantomData<fn() -> T>,
}

/// A parser of `T` whose names are `names` (e.g. `Algorithm::ALL.map(Algorithm::name)`).
pub fn one_of<T>(names: impl IntoIterator<Item = &'static str>) -> OneOf<T> {
    OneOf { names: names.into_iter().collect(), value: PhantomData }
}

impl<T> TypedValueParser for OneOf<T>
where
    T: FromStr + Clone + Send + Sync + 'static,
    T::Err: Into<Box<dyn std::error::Error + Send + Sync + 'static>>,
{
    type Value = T;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<T, clap::Error> {
        (|s: &str| s.parse::<T>()).parse_ref(cmd, arg, value)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(self.names.iter().map(|&n| PossibleValue::new(n))))
    }
}

/// Applies `NAME=VALUE` settings in order with `set(name, value)`; errors name the flag and the setting.
pub fn set_each<E: std::fmt::Display>(
    flag: &str,
    settings: &[String],
    mut set: impl FnMut(&str, &str) -> Result<(), E>,
) -> Result<()> {
    for kv in settings {
        let Some((name, value)) = kv.split_once('=') else {
            bail!("{flag} {kv}: expected NAME=VALUE");
        };
        set(name.trim(), value).map_err(|e| anyhow::anyhow!("{flag} {kv}: {e}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use mrslam_merge::Algorithm;

    #[derive(Parser)]
    struct Cli {
        #[arg(long, value_parser = one_of::<Algorithm>(Algorithm::ALL.map(Algorithm::name)))]
        algorithm: Algorithm,
    }

    #[test]
    fn a_name_is_read_by_the_enums_parser_and_a_bad_one_refused_with_its_message() {
        assert_eq!(Cli::try_parse_from(["x", "--algorithm", "rmap"]).unwrap().algorithm, Algorithm::Rmap);
        let err = Cli::try_parse_from(["x", "--algorithm", "magic"]).err().unwrap().to_string();
        assert!(err.contains("unknown algorithm `magic`"), "{err}");
    }

    #[test]
    fn settings_are_applied_in_order_and_a_bad_one_names_the_flag() {
        let mut seen = Vec::new();
        let ok: Result<(), String> = Ok(());
        set_each("--set", &["a=1".into(), " b =2".into()], |n, v| {
            seen.push(format!("{n}:{v}"));
            ok.clone()
        })
        .unwrap();
        assert_eq!(seen, ["a:1", "b:2"]);
        let err = set_each("--set", &["a".into()], |_, _| ok.clone()).unwrap_err().to_string();
        assert_eq!(err, "--set a: expected NAME=VALUE");
        let err = set_each("--set", &["a=x".into()], |_, _| Err("not a number")).unwrap_err().to_string();
        assert_eq!(err, "--set a=x: not a number");
    }
}
