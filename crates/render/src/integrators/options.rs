//! Method options as plain data: each method declares its options ([`OptionSpec`]: name,
//! default, help) once, and builds its typed settings from the values given
//! ([`MethodOptions`]), so the command line, `compare` and library users share one definition
//! of every flag and its default.

use super::Method;
use crate::Error;
use std::collections::BTreeMap;
use std::str::FromStr;

/// Whether an option takes a value or is a switch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OptionKind {
    /// `--name VALUE`.
    Value,
    /// `--name` (off unless given).
    Flag,
}

/// One option of a method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OptionSpec {
    /// The flag without its dashes (`spp`, `max-samples`).
    pub name: &'static str,
    /// Value placeholder in help (`N`, `MFP`).
    pub value_name: &'static str,
    /// The default value as text (parsed like a given value; empty for flags).
    pub default: &'static str,
    /// Help text.
    pub help: &'static str,
    /// Value or switch.
    pub kind: OptionKind,
    /// The accepted values, from their one source (a registry's names), listed in the help;
    /// empty when any value of the option's type is accepted. The method still checks the
    /// value when it parses it.
    pub values: &'static [&'static str],
}

/// Option values given by a caller, by option name; options not given take their defaults.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MethodOptions {
    values: BTreeMap<String, String>,
}

impl MethodOptions {
    /// No options given: every option at its default.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets option `name` to `value` (for a flag, any value turns it on).
    pub fn set(&mut self, name: &str, value: impl ToString) -> &mut Self {
        self.values.insert(name.to_string(), value.to_string());
        self
    }

    /// This set with option `name` at `value`.
    pub fn with(mut self, name: &str, value: impl ToString) -> Self {
        self.set(name, value);
        self
    }

    /// The names given.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.values.keys().map(String::as_str)
    }

    /// The value given for option `name` (empty for a switch), if it was given.
    pub fn value(&self, name: &str) -> Option<&str> {
        self.values.get(name).map(String::as_str)
    }

    /// Fails when an option given is not one of `method`'s.
    pub fn check_known(&self, method: &Method) -> Result<(), Error> {
        for name in self.names() {
            if !method.options.iter().any(|o| o.name == name) {
                let known: Vec<String> = method
                    .options
                    .iter()
                    .map(|o| format!("--{}", o.name))
                    .collect();
                return Err(Error::Input(format!(
                    "--{name} is not an option of method {} (its options: {})",
                    method.name,
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                )));
            }
        }
        Ok(())
    }

    /// The value of option `name` of `specs` (given, or its default), parsed.
    pub fn get<T: FromStr>(&self, specs: &[OptionSpec], name: &str) -> Result<T, Error>
    where
        T::Err: std::fmt::Display,
    {
        let spec = specs
            .iter()
            .find(|s| s.name == name)
            .ok_or_else(|| Error::Input(format!("internal: no option --{name} is declared")))?;
        let text = self.values.get(name).map_or(spec.default, String::as_str);
        text.trim()
            .parse::<T>()
            .map_err(|e| Error::Input(format!("--{name}: invalid value `{text}`: {e}")))
    }

    /// Whether switch `name` is on.
    pub fn flag(&self, name: &str) -> bool {
        self.values.contains_key(name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPECS: &[OptionSpec] = &[
        OptionSpec {
            name: "n",
            value_name: "N",
            default: "16",
            help: "",
            kind: OptionKind::Value,
            values: &[],
        },
        OptionSpec {
            name: "fast",
            value_name: "",
            default: "",
            help: "",
            kind: OptionKind::Flag,
            values: &[],
        },
    ];

    #[test]
    fn defaults_values_flags_and_parse_errors() {
        let none = MethodOptions::new();
        assert_eq!(none.get::<u32>(SPECS, "n").unwrap(), 16);
        assert!(!none.flag("fast"));
        let given = MethodOptions::new().with("n", 3).with("fast", "");
        assert_eq!(given.get::<u32>(SPECS, "n").unwrap(), 3);
        assert!(given.flag("fast"));
        let bad = MethodOptions::new().with("n", "x").get::<u32>(SPECS, "n");
        let msg = bad.unwrap_err().to_string();
        assert!(msg.starts_with("--n: invalid value `x`"), "{msg}");
        assert!(none.get::<u32>(SPECS, "missing").is_err());
    }
}
