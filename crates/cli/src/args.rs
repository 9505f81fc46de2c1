//! Options shared by several subcommands: the medium (`--preset` or coefficients) and
//! `R,G,B` triples.

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{ArgGroup, Args};
use sss_bssrdf::{MediumSpec, Rgb};
use sss_render::Error;
use std::str::FromStr;

/// The medium of `sss profile` and `sss kernel`: a preset, or coefficients.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("medium").required(true).args(["preset", "sigma_a"])))]
pub struct MediumArgs {
    /// A measured material (see `sss presets`); g = 0 and sigma_s = sigma_s'.
    #[arg(long, conflicts_with_all = ["sigma_a", "sigma_s", "g"])]
    pub preset: Option<String>,
    /// Absorption coefficients R,G,B in 1/mm.
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb, allow_hyphen_values = true, requires = "sigma_s")]
    pub sigma_a: Option<Rgb>,
    /// Scattering coefficients R,G,B in 1/mm.
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb, allow_hyphen_values = true, requires = "sigma_a")]
    pub sigma_s: Option<Rgb>,
    /// Henyey-Greenstein anisotropy (with --sigma-a/--sigma-s) [default: 0].
    #[arg(long, allow_hyphen_values = true)]
    pub g: Option<f64>,
    /// Relative index of refraction [default: 1.3].
    #[arg(long, allow_hyphen_values = true)]
    pub eta: Option<f64>,
}

impl MediumArgs {
    /// The medium these arguments name (without η, which callers pass on separately).
    pub fn spec(&self) -> Result<MediumSpec, Error> {
        match (&self.preset, self.sigma_a, self.sigma_s) {
            (Some(name), None, None) => Ok(MediumSpec::Preset(name.clone())),
            (None, Some(sigma_a), Some(sigma_s)) => Ok(MediumSpec::Coefficients {
                sigma_a,
                sigma_s,
                g: self.g.unwrap_or(0.0),
            }),
            _ => Err(Error::Input(
                "give either --preset NAME or both --sigma-a R,G,B and --sigma-s R,G,B".into(),
            )),
        }
    }
}

/// `what`, then the models' names from their one list ([`sss_bssrdf::ModelKind::ALL`]): the
/// help of `--model`.
pub fn model_help(what: &str) -> String {
    let names: Vec<&str> = sss_bssrdf::ModelKind::ALL
        .iter()
        .map(|k| k.name())
        .collect();
    format!("{what} (one of: {})", names.join(", "))
}

/// A value parser that accepts exactly `names` (listed in the help and in the error for any
/// other word) and parses the word into a `T` (a library type with `FromStr` whose names these
/// are).
pub fn names_parser<T>(names: impl IntoIterator<Item = &'static str>) -> impl TypedValueParser
where
    T: FromStr + Clone + Send + Sync + 'static,
    T::Err: std::error::Error + Send + Sync + 'static,
{
    PossibleValuesParser::new(names).try_map(|s| s.parse::<T>())
}

/// Parses `R,G,B` (three numbers separated by commas; spaces allowed).
pub fn parse_rgb(s: &str) -> Result<Rgb, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers R,G,B, got {} value(s)",
            parts.len()
        ));
    }
    let mut v = [0.0; 3];
    for (slot, p) in v.iter_mut().zip(&parts) {
        *slot = p
            .parse::<f64>()
            .map_err(|_| format!("'{p}' is not a number (expected R,G,B)"))?;
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_parsing() {
        assert_eq!(parse_rgb("1,2.5, 3e-1").unwrap(), [1.0, 2.5, 0.3]);
        assert!(parse_rgb("1,2").is_err());
        assert!(parse_rgb("1,2,3,4").is_err());
        assert!(parse_rgb("1,x,3").is_err());
        assert!(parse_rgb("-1,2,3").is_ok(), "range is checked by Medium");
    }

    #[test]
    fn names_parser_accepts_the_names_only() {
        use clap::Parser;
        use sss_bssrdf::profile_rows::ProfileModel;
        #[derive(Parser)]
        struct T {
            #[arg(long, value_parser = names_parser::<ProfileModel>(ProfileModel::ALL.map(|m| m.name())))]
            model: ProfileModel,
        }
        for m in ProfileModel::ALL {
            let t = T::try_parse_from(["t", "--model", m.name()]).unwrap();
            assert_eq!(t.model, m);
        }
        let e = T::try_parse_from(["t", "--model", "pdb"])
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("monte-carlo") && e.contains("pdb"), "{e}");
    }
}
