//! Method options as plain data: each method declares its options ([`OptionSpec`]: name,
//! default, help) once, and builds its typed settings from the values given
//! ([`MethodOptions`]), so the command line, `compare` and library users share one definition
//! of every flag and its default.

use super::Method;
use crate::Error;
use crate::irradiance::IrradianceSettings;
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

/// Options that were renamed, with the names that replace them and what each means: a caller
/// who gives an old name is refused with a message naming the new one its method takes
/// ([`MethodOptions::check_known`]). `--eps` meant a solid angle for the trees and a relative
/// error for the many-light methods; each quantity now has its own name.
pub const RENAMED: [(&str, &[(&str, &str)]); 1] = [(
    "eps",
    &[
        ("solid-angle", "is the tree methods' solid-angle threshold"),
        (
            "rel-error",
            "is the many-light methods' relative error target",
        ),
    ],
)];

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

    /// The options given that `method` takes, and the names of those it does not (which a
    /// caller ignores with a warning, as `sss render` does another method's flag).
    pub fn partition(&self, method: &Method) -> (MethodOptions, Vec<String>) {
        let mut taken = MethodOptions::new();
        let mut others = Vec::new();
        for (name, value) in &self.values {
            // A renamed option stays with the method, which refuses it naming the new one.
            let renamed = RENAMED.iter().any(|(old, _)| old == name);
            if renamed || method.options.iter().any(|o| o.name == name) {
                taken.set(name, value);
            } else {
                others.push(name.clone());
            }
        }
        (taken, others)
    }

    /// Fails when an option given is not one of `method`'s.
    pub fn check_known(&self, method: &Method) -> Result<(), Error> {
        for name in self.names() {
            if let Some((_, new)) = RENAMED.iter().find(|(old, _)| *old == name) {
                let meanings: Vec<String> = new
                    .iter()
                    .map(|(n, what)| format!("--{n} {what}"))
                    .collect();
                let taken = new
                    .iter()
                    .find(|(n, _)| method.options.iter().any(|o| o.name == *n));
                let which = match taken {
                    Some((n, _)) => format!("method {} takes --{n}", method.name),
                    None => format!("method {} takes neither", method.name),
                };
                return Err(Error::Input(format!(
                    "--{name} is no longer an option: {which} ({})",
                    meanings.join("; ")
                )));
            }
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

// The option specs more than one method takes, by name: a method lists the ones it takes in
// its own `OPTIONS`, so reordering one method's flags never rewires another's.

/// `--spacing MFP`: irradiance sample spacing (the point sums: `exact`, `single-tree`,
/// `dual-tree`, `dual-tree-fmm`).
pub const SPACING: OptionSpec = OptionSpec {
    name: "spacing",
    value_name: "MFP",
    default: "0.5",
    help: "Irradiance sample spacing in units of the smallest reduced mean free path",
    kind: OptionKind::Value,
    values: &[],
};

/// `--max-samples N`: the cap on irradiance samples per object (the point sums).
pub const MAX_SAMPLES: OptionSpec = OptionSpec {
    name: "max-samples",
    value_name: "N",
    default: "100000",
    help: "At most this many irradiance samples per object (the spacing grows to respect it)",
    kind: OptionKind::Value,
    values: &[],
};

/// `--bounces N`: bounces of the light the surfaces trade, gathered into the irradiance
/// samples (the point sums; [`crate::integrators::point_sums::interreflection`]).
pub const BOUNCES: OptionSpec = OptionSpec {
    name: "bounces",
    value_name: "N",
    default: "0",
    help: "Bounces of the light the surfaces trade (interreflection), gathered into the \
           irradiance samples (0: direct light only)",
    kind: OptionKind::Value,
    values: &[],
};

/// The irradiance-sample options every point sum takes first: [`SPACING`], [`MAX_SAMPLES`],
/// [`BOUNCES`].
pub const SAMPLE_OPTIONS: [OptionSpec; 3] = [SPACING, MAX_SAMPLES, BOUNCES];

/// `--solid-angle E` of the tree traversals (`single-tree`, `dual-tree`, `dual-tree-fmm`):
/// the solid-angle threshold ε of Jensen & Buhler 2002 and Milaenen et al. 2019.
pub const SOLID_ANGLE: OptionSpec = OptionSpec {
    name: "solid-angle",
    value_name: "E",
    default: "0.05",
    help: "Solid-angle threshold ε: a node of irradiance samples stands for all of them \
           when A / d² < ε (smaller is more accurate and slower)",
    kind: OptionKind::Value,
    values: &[],
};

/// The values of `--selection`, as the help and the error list them: `bssrdf` (also spelt
/// `bssrdf-aware`) and `max-extent`.
pub const SELECTIONS: [&str; 2] = ["bssrdf", "max-extent"];

/// `--selection` of the many-light estimator (`manylight`, `sparse-manylight`).
pub const SELECTION: OptionSpec = OptionSpec {
    name: "selection",
    value_name: "SELECTION",
    default: "bssrdf",
    help: "Cluster to refine: BSSRDF-aware (Nabata & Iwasaki Eq. 10-13) or the largest box (Max-Extent)",
    kind: OptionKind::Value,
    values: &SELECTIONS,
};

/// `--max-triplets N` of the many-light estimator (`manylight`, `sparse-manylight`).
pub const MAX_TRIPLETS: OptionSpec = OptionSpec {
    name: "max-triplets",
    value_name: "N",
    default: "200000",
    help: "Cap on the triplets of one pixel and object (pixels at the cap are counted and warned about)",
    kind: OptionKind::Value,
    values: &[],
};

/// `--dark-floor F` of the many-light estimator (`manylight`, `sparse-manylight`).
///
/// Its default, 10⁻⁶, is about 20 stops below the frame's bright level, darker than any display
/// or tone curve shows. Pixels that dark (in a point-lit head's own shadow, 10⁻⁸ of the median)
/// otherwise refine to the triplet cap for a relative error nobody sees: the triplets' bounds
/// ignore visibility, so the refinement splits the shadowed clusters next to the pixel, whose
/// samples are all 0, long before the faint far ones that carry its value.
pub const DARK_FLOOR: OptionSpec = OptionSpec {
    name: "dark-floor",
    value_name: "F",
    default: "1e-6",
    help: "Pixels darker than F times the frame's bright level (the 90th percentile of a 32-pixel pilot at rel-error 0.2) stop at an absolute error of rel-error * F * that level instead of rel-error times their own value; 0: the paper's purely relative criterion",
    kind: OptionKind::Value,
    values: &[],
};

/// `--rel-error E` of the Student-t estimators (`manylight`, `eelc`): the relative error
/// target ε of Nabata & Iwasaki.
pub const REL_ERROR: OptionSpec = OptionSpec {
    name: "rel-error",
    value_name: "E",
    default: "0.02",
    help: "Relative error threshold: refine each pixel until its Student-t interval is below E times its value (the paper uses 0.02)",
    kind: OptionKind::Value,
    values: &[],
};

/// `--alpha A`: the confidence level of the Student-t interval (`manylight`, `eelc`).
pub const ALPHA: OptionSpec = OptionSpec {
    name: "alpha",
    value_name: "A",
    default: "0.95",
    help: "Confidence level of the interval, in (0, 1)",
    kind: OptionKind::Value,
    values: &[],
};

/// `--vpls N`: VPLs per sun, quad or environment light (`manylight`, `mdlc`, `eelc`).
pub const VPLS: OptionSpec = OptionSpec {
    name: "vpls",
    value_name: "N",
    default: "1024",
    help: "VPLs per sun, quad or environment light (a point or directional light is one VPL)",
    kind: OptionKind::Value,
    values: &[],
};

/// `--irradiance-points N` (`mdlc`, `eelc`).
pub const IRRADIANCE_POINTS: OptionSpec = OptionSpec {
    name: "irradiance-points",
    value_name: "N",
    default: "4096",
    help: "Irradiance points drawn per shading point before the pixel is estimated (the paper uses 4096)",
    kind: OptionKind::Value,
    values: &[],
};

/// `--uniform-points` (`mdlc`, `eelc`).
pub const UNIFORM_POINTS: OptionSpec = OptionSpec {
    name: "uniform-points",
    value_name: "",
    default: "",
    help: "Draw the irradiance points uniformly by area over the object instead of by BSSRDF importance sampling (probe rays)",
    kind: OptionKind::Flag,
    values: &[],
};

/// `--probe-energy F` of `pathtrace`, whose default is also the probe sampler's for the
/// methods that draw points with it ([`crate::probe::default_probe_energy`]).
pub const PROBE_ENERGY: OptionSpec = OptionSpec {
    name: "probe-energy",
    value_name: "F",
    default: "0.9999",
    help: "Fraction of each channel's profile energy inside its probe sphere, in (0, 1); the \
           energy beyond the largest sphere is never sampled (stat probe_missed_energy)",
    kind: OptionKind::Value,
    values: &[],
};

/// `--max-pairs N` (`mdlc`, `eelc`).
pub const MAX_PAIRS: OptionSpec = OptionSpec {
    name: "max-pairs",
    value_name: "N",
    default: "200000",
    help: "Cap on the cluster pairs (gather cluster x light cluster) of one pixel and object (pixels at the cap are counted and warned about)",
    kind: OptionKind::Value,
    values: &[],
};

/// The declared default of option `name` of `specs`, parsed: what a settings type's
/// `Default` reads, so that each default is stated once, in its [`OptionSpec`]. Panics only
/// when a declaration's own default does not parse (a bug the registry's contract test
/// catches: every method builds from its declared defaults).
pub(crate) fn declared<T: FromStr>(specs: &[OptionSpec], name: &str) -> T
where
    T::Err: std::fmt::Display,
{
    match MethodOptions::new().get(specs, name) {
        Ok(v) => v,
        Err(e) => panic!("the declared default of --{name} does not parse: {e}"),
    }
}

/// The settings `build` makes of no options given, i.e. of the declared defaults: a settings
/// type's `Default` when its defaults are all options. Panics only when the declared defaults
/// do not build (a bug the registry's contract test catches).
pub(crate) fn from_declared<T>(
    what: &str,
    build: impl FnOnce(&MethodOptions) -> Result<T, Error>,
) -> T {
    match build(&MethodOptions::new()) {
        Ok(v) => v,
        Err(e) => panic!("the declared defaults of {what} do not build: {e}"),
    }
}

/// Reads and checks the irradiance-sample options ([`SAMPLE_OPTIONS`]).
pub fn sample_settings(o: &MethodOptions) -> Result<IrradianceSettings, Error> {
    let spacing: f64 = o.get(&SAMPLE_OPTIONS, "spacing")?;
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(Error::Input(format!(
            "--spacing must be positive, got {spacing}"
        )));
    }
    let bounces: u32 = o.get(&SAMPLE_OPTIONS, "bounces")?;
    let most = crate::integrators::point_sums::interreflection::MAX_BOUNCES;
    if bounces > most {
        return Err(Error::Input(format!(
            "--bounces must be at most {most}, got {bounces}"
        )));
    }
    Ok(IrradianceSettings {
        spacing_mfp: spacing,
        max_samples: o.get(&SAMPLE_OPTIONS, "max-samples")?,
        bounces,
        ..IrradianceSettings::default()
    })
}

/// Reads and checks the threshold `name` of `options` (`solid-angle` or `rel-error`: finite,
/// ≥ 0; every method's ε has that range).
pub fn eps_option(o: &MethodOptions, options: &[OptionSpec], name: &str) -> Result<f64, Error> {
    let eps: f64 = o.get(options, name)?;
    if !(eps.is_finite() && eps >= 0.0) {
        return Err(Error::Input(format!(
            "--{name} must be finite and >= 0, got {eps}"
        )));
    }
    Ok(eps)
}

/// Reads and checks the confidence level `--alpha` of `options` (in (0, 1)).
pub fn alpha_option(o: &MethodOptions, options: &[OptionSpec]) -> Result<f64, Error> {
    let alpha: f64 = o.get(options, "alpha")?;
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(Error::Input(format!(
            "--alpha must be in (0, 1), got {alpha}"
        )));
    }
    Ok(alpha)
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

    /// `--eps` is refused by every method, naming the option that replaced it there: the
    /// trees' solid angle, the many-light methods' relative error, or neither; a method that
    /// is only handed it through `partition` refuses it too (it is not ignored as another
    /// method's option).
    #[test]
    fn the_old_eps_is_refused_naming_its_replacement() {
        let trees = ["single-tree", "dual-tree", "dual-tree-fmm"];
        let vpl = ["manylight", "sparse-manylight", "mdlc", "eelc"];
        let given = MethodOptions::new().with("eps", 0.1).with("taps", 5);
        for m in crate::integrators::METHODS {
            let (taken, others) = given.partition(m);
            assert!(taken.names().any(|n| n == "eps"), "{}", m.name);
            // Another method's option is set aside (for a warning), the method's own kept.
            let takes_taps = m.options.iter().any(|o| o.name == "taps");
            let expected: &[&str] = if takes_taps { &[] } else { &["taps"] };
            assert_eq!(others, expected, "{}", m.name);
            assert_eq!(taken.names().any(|n| n == "taps"), takes_taps, "{}", m.name);
            let msg = crate::integrators::build(m.name, &taken)
                .err()
                .unwrap_or_else(|| panic!("{} took --eps", m.name))
                .to_string();
            assert!(msg.starts_with("--eps is no longer an option: "), "{msg}");
            let new = if trees.contains(&m.name) {
                "takes --solid-angle"
            } else if vpl.contains(&m.name) {
                "takes --rel-error"
            } else {
                "takes neither"
            };
            assert!(msg.contains(&format!("method {} {new}", m.name)), "{msg}");
            // Every method takes at most one of the new names, and the new name builds.
            let takes: Vec<&str> = ["solid-angle", "rel-error"]
                .into_iter()
                .filter(|n| m.options.iter().any(|o| o.name == *n))
                .collect();
            assert!(takes.len() <= 1, "{}: {takes:?}", m.name);
            for n in takes {
                crate::integrators::build(m.name, &MethodOptions::new().with(n, 0.1)).unwrap();
            }
        }
    }

    /// The thresholds are read under the name asked for, and NaN, infinite or negative values
    /// are refused naming that flag.
    #[test]
    fn thresholds_are_read_and_checked_by_name() {
        let specs = [SOLID_ANGLE, REL_ERROR];
        let none = MethodOptions::new();
        assert_eq!(eps_option(&none, &specs, "solid-angle").unwrap(), 0.05);
        assert_eq!(eps_option(&none, &specs, "rel-error").unwrap(), 0.02);
        let given = MethodOptions::new()
            .with("solid-angle", 0.3)
            .with("rel-error", 0);
        assert_eq!(eps_option(&given, &specs, "solid-angle").unwrap(), 0.3);
        assert_eq!(eps_option(&given, &specs, "rel-error").unwrap(), 0.0);
        for bad in ["-0.1", "NaN", "inf"] {
            let o = MethodOptions::new().with("rel-error", bad);
            let msg = eps_option(&o, &specs, "rel-error").unwrap_err().to_string();
            assert!(
                msg.starts_with("--rel-error must be finite and >= 0"),
                "{msg}"
            );
        }
    }
}
