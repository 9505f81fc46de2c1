//! The command-line reference as Markdown, generated from the clap definitions ([`Cli`]) and
//! the method registry ([`METHODS`]), so the documentation cannot drift from the program:
//! `cargo xtask docs` writes it into `docs/cli.md`, and a test fails when the committed file
//! differs from what this module generates.

use crate::Cli;
use clap::CommandFactory;
use sss_render::integrators::{METHODS, OptionKind};
use std::fmt::Write as _;

/// The `sss` program and each subcommand's `--help` text, then one table per rendering method
/// (its flags, defaults and help, from [`METHODS`]). Headings start at level 2, so a caller can
/// put its own title and sections around it.
pub fn markdown() -> String {
    let mut cmd = Cli::command();
    cmd.build();
    let mut out = String::new();
    let _ = writeln!(out, "## `sss`\n");
    help_block(&mut out, &cmd.render_long_help().to_string());
    for sub in cmd.get_subcommands() {
        if sub.get_name() == "help" {
            continue;
        }
        let _ = writeln!(out, "## `sss {}`\n", sub.get_name());
        let mut sub = sub.clone();
        help_block(&mut out, &sub.render_long_help().to_string());
    }
    let _ = writeln!(
        out,
        "## Rendering methods\n\n`sss render --method NAME` takes the options of its method; \
         an option of another method is an input error. Each method's options and defaults, \
         from the registry:\n"
    );
    for m in METHODS {
        let _ = writeln!(out, "### `{}`\n\n{}.\n", m.name, m.about);
        if m.options.is_empty() {
            let _ = writeln!(out, "No options.\n");
            continue;
        }
        let _ = writeln!(out, "| option | default | meaning |\n|---|---|---|");
        for o in m.options {
            let flag = match o.kind {
                OptionKind::Value => format!("`--{} {}`", o.name, o.value_name),
                OptionKind::Flag => format!("`--{}`", o.name),
            };
            let default = match o.kind {
                OptionKind::Flag => "off".to_string(),
                OptionKind::Value => format!("`{}`", o.default),
            };
            let mut help = o.help.replace('|', "\\|");
            if !o.values.is_empty() {
                let _ = write!(help, " (one of: {})", o.values.join(", "));
            }
            let _ = writeln!(out, "| {flag} | {default} | {help} |");
        }
        out.push('\n');
    }
    out
}

/// Appends `help` as a fenced text block, trailing spaces removed (also used by `cargo xtask
/// docs` for its own help).
pub fn help_block(out: &mut String, help: &str) {
    out.push_str("```text\n");
    for line in help.trim_end().lines() {
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out.push_str("```\n\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every subcommand and every method has its section, and every option of every method
    /// its row with its default: the reference covers the whole registry.
    #[test]
    fn every_command_method_and_option_appears() {
        let text = markdown();
        for sub in ["profile", "presets", "render", "diff", "kernel", "filter"] {
            assert!(text.contains(&format!("## `sss {sub}`")), "{sub} missing");
        }
        for m in METHODS {
            let head = format!("### `{}`", m.name);
            let at = text
                .find(&head)
                .unwrap_or_else(|| panic!("{} has no section", m.name));
            // The method's own section: up to the next heading.
            let section = &text[at + head.len()..];
            let section = &section[..section.find("\n#").unwrap_or(section.len())];
            for o in m.options {
                let flag = match o.kind {
                    OptionKind::Value => format!("| `--{} {}` |", o.name, o.value_name),
                    OptionKind::Flag => format!("| `--{}` |", o.name),
                };
                let row = section
                    .lines()
                    .find(|l| l.starts_with(&flag))
                    .unwrap_or_else(|| panic!("--{} of {} has no row", o.name, m.name));
                if o.kind == OptionKind::Value {
                    assert!(row.contains(&format!("| `{}` |", o.default)), "{row}");
                }
            }
            assert_eq!(
                section.lines().filter(|l| l.starts_with("| `--")).count(),
                m.options.len(),
                "{}: one row per option",
                m.name
            );
        }
        // A help text's own `|` cannot break its table row.
        assert!(
            text.lines()
                .all(|l| !l.starts_with("| `") || l.matches(" | ").count() >= 2)
        );
    }
}
