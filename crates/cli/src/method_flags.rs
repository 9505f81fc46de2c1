//! Command-line flags generated from the method registry (`sss_render::integrators::METHODS`):
//! every option a method declares becomes `--<name>`, so a new method's flags appear in
//! `sss render` (and its help) without touching this crate. Only the values actually given
//! are recorded; defaults come from the method's own declaration.

use clap::builder::PossibleValuesParser;
use clap::{Arg, ArgAction, ArgMatches, Command};
use sss_render::integrators::options::RENAMED;
use sss_render::integrators::{METHODS, MethodOptions, OptionKind, OptionSpec};
use std::marker::PhantomData;

/// Which options a flag set offers.
pub trait FlagSet {
    /// The options, each once, with the methods that use it.
    fn specs() -> Vec<(OptionSpec, Vec<&'static str>)>;

    /// Old option names still accepted on the command line (hidden from the help) so that the
    /// method refuses them with a message naming the new one, instead of clap's guess.
    fn renamed() -> Vec<&'static str> {
        Vec::new()
    }
}

/// Every option of every registered method (`sss render`).
#[derive(Clone, Debug, Default)]
pub struct AllMethods;

impl FlagSet for AllMethods {
    fn specs() -> Vec<(OptionSpec, Vec<&'static str>)> {
        let mut out: Vec<(OptionSpec, Vec<&'static str>)> = Vec::new();
        for m in METHODS {
            for spec in m.options {
                match out.iter_mut().find(|(s, _)| s.name == spec.name) {
                    Some((_, users)) => users.push(m.name),
                    None => out.push((*spec, vec![m.name])),
                }
            }
        }
        out
    }

    fn renamed() -> Vec<&'static str> {
        RENAMED.iter().map(|(old, _)| *old).collect()
    }
}

/// The separable method's options alone (`sss filter`).
#[derive(Clone, Debug, Default)]
pub struct SeparableOnly;

impl FlagSet for SeparableOnly {
    fn specs() -> Vec<(OptionSpec, Vec<&'static str>)> {
        sss_render::integrators::separable::OPTIONS
            .iter()
            .map(|s| (*s, vec!["separable"]))
            .collect()
    }
}

/// The method options given on the command line.
#[derive(Clone, Debug, Default)]
pub struct MethodFlags<S: FlagSet> {
    /// Values given, by option name.
    pub options: MethodOptions,
    set: PhantomData<S>,
}

/// The names of the registered methods, for `--method`.
pub fn method_parser() -> PossibleValuesParser {
    PossibleValuesParser::new(METHODS.iter().map(|m| m.name))
}

/// The declarations of option `name` by the methods `users`, grouped by (help, default): one
/// group when they agree; several when methods word one quantity their own way (e.g.
/// `--rel-error`, whose help says how `manylight`, `sparse-manylight` and `mdlc` apply it).
fn variants(name: &str, users: &[&str]) -> Vec<(OptionSpec, Vec<&'static str>)> {
    let mut out: Vec<(OptionSpec, Vec<&'static str>)> = Vec::new();
    for m in METHODS.iter().filter(|m| users.contains(&m.name)) {
        let Some(o) = m.options.iter().find(|o| o.name == name) else {
            continue;
        };
        match out
            .iter_mut()
            .find(|(s, _)| s.help == o.help && s.default == o.default)
        {
            Some((_, ms)) => ms.push(m.name),
            None => out.push((*o, vec![m.name])),
        }
    }
    out
}

/// An option's help text, with its accepted values ([`OptionSpec::values`]) when it lists them.
fn help_text(spec: &OptionSpec) -> String {
    if spec.values.is_empty() {
        spec.help.to_string()
    } else {
        format!("{} (one of: {})", spec.help, spec.values.join(", "))
    }
}

fn arg(spec: &OptionSpec, users: &[&str]) -> Arg {
    let used_by = |users: &[&str]| {
        if users.len() == METHODS.len() {
            String::new()
        } else {
            format!(" ({})", users.join(", "))
        }
    };
    let groups = variants(spec.name, users);
    let arg = Arg::new(spec.name).long(spec.name);
    match spec.kind {
        OptionKind::Flag => {
            arg.action(ArgAction::SetTrue)
                .help(format!("{}{}", help_text(spec), used_by(users)))
        }
        OptionKind::Value => {
            let help = if groups.len() <= 1 {
                format!(
                    "{}{} [default: {}]",
                    help_text(spec),
                    used_by(users),
                    spec.default
                )
            } else {
                groups
                    .iter()
                    .map(|(o, ms)| {
                        format!(
                            "{}: {} [default: {}]",
                            ms.join(", "),
                            help_text(o),
                            o.default
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; ")
            };
            arg.action(ArgAction::Set)
                .value_name(spec.value_name)
                .allow_hyphen_values(true)
                .help(help)
        }
    }
}

impl<S: FlagSet> clap::FromArgMatches for MethodFlags<S> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut flags = MethodFlags {
            options: MethodOptions::new(),
            set: PhantomData,
        };
        flags.update_from_arg_matches(m)?;
        Ok(flags)
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        for (spec, _) in S::specs() {
            match spec.kind {
                OptionKind::Flag => {
                    if m.get_flag(spec.name) {
                        self.options.set(spec.name, "");
                    }
                }
                OptionKind::Value => {
                    if let Some(v) = m.get_one::<String>(spec.name) {
                        self.options.set(spec.name, v);
                    }
                }
            }
        }
        for old in S::renamed() {
            if let Some(v) = m.get_one::<String>(old) {
                self.options.set(old, v);
            }
        }
        Ok(())
    }
}

impl<S: FlagSet> clap::Args for MethodFlags<S> {
    fn augment_args(mut cmd: Command) -> Command {
        for (spec, users) in S::specs() {
            cmd = cmd.arg(arg(&spec, &users));
        }
        for old in S::renamed() {
            cmd = cmd.arg(
                Arg::new(old)
                    .long(old)
                    .hide(true)
                    .action(ArgAction::Set)
                    .allow_hyphen_values(true),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Options shared by several methods must be the same kind of flag (a switch in one and a
    /// value in another could not share `--name`); their help and default may differ, and
    /// the help then says which applies to which method.
    #[test]
    fn shared_options_agree_between_methods() {
        for m in METHODS {
            for spec in m.options {
                for other in METHODS {
                    if let Some(o) = other.options.iter().find(|o| o.name == spec.name) {
                        assert_eq!(
                            (o.kind, o.value_name),
                            (spec.kind, spec.value_name),
                            "--{} differs between {} and {}",
                            spec.name,
                            m.name,
                            other.name
                        );
                    }
                }
            }
        }
        // --rel-error is worded three ways: the help names each, with its default.
        let users: Vec<&str> = METHODS
            .iter()
            .filter(|m| m.options.iter().any(|o| o.name == "rel-error"))
            .map(|m| m.name)
            .collect();
        let groups = variants("rel-error", &users);
        assert!(groups.len() > 1, "{groups:?}");
        {
            let spec = groups[0].0;
            let help = arg(&spec, &users)
                .get_help()
                .map(|h| h.to_string())
                .unwrap_or_default();
            for (o, ms) in &groups {
                assert!(
                    help.contains(o.default) && ms.iter().all(|m| help.contains(m)),
                    "{help}"
                );
            }
        }
    }

    /// Every method builds from its declared defaults, and every sweep value builds too.
    #[test]
    fn every_method_builds_from_defaults_and_sweep_values() {
        for m in METHODS {
            let i = (m.build)(&MethodOptions::new()).unwrap();
            assert_eq!(i.name(), m.name);
            assert!(
                m.options.iter().any(|o| o.name == m.sweep.option),
                "{}",
                m.name
            );
            for quick in [false, true] {
                for v in (m.sweep.values)(quick) {
                    let opts = MethodOptions::new().with(m.sweep.option, v);
                    (m.build)(&opts).unwrap_or_else(|e| panic!("{} {v}: {e}", m.name));
                }
            }
        }
    }
}
