//! The loading state ([`Ctx`]) and how errors are made: an error at a key finds its line in
//! the document's span index; a toml error is given the line and key of its span.

use super::LoadOptions;
use crate::format::SpanIndex;
use crate::{SceneError, SceneErrorKind};
use std::path::Path;

/// Loading state: the file, its span index, where meshes are searched, warnings so far.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
    pub(super) spans: SpanIndex,
    pub(super) base_dir: Option<&'a Path>,
    pub(super) opts: &'a LoadOptions,
    pub(super) warnings: Vec<String>,
}

/// A number as written in messages (`0.5`, `NaN`, `inf`).
pub(super) fn fmt_num(v: f64) -> String {
    format!("{v}")
}

pub(super) fn list(items: &[&str]) -> String {
    items
        .iter()
        .map(|s| format!("`{s}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl Ctx<'_> {
    /// An `Invalid` error at key path `key` (its line looked up in the document).
    pub(super) fn err(&self, key: &str, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            line: self.spans.line(key),
            key: Some(key.to_string()),
            message: message.into(),
            kind: SceneErrorKind::Invalid,
        }
    }

    /// An error of the scene as a whole (no key).
    pub(super) fn err_scene(&self, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            line: None,
            key: None,
            message: message.into(),
            kind: SceneErrorKind::Invalid,
        }
    }

    /// A toml syntax or structure error: its message, the line of its span, and the key it
    /// points at (for `unknown field` and `missing field`, the key named in the message).
    pub(super) fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let message = e.message().trim().to_string();
        let (mut line, mut key) = (None, None);
        if let Some(span) = e.span() {
            line = Some(self.spans.line_of_offset(span.start));
            key = self.spans.path_at(&span).map(str::to_string);
        }
        if let Some(missing) = backticked(&message, "missing field `") {
            let path = match &key {
                Some(k) => format!("{k}.{missing}"),
                None => missing.to_string(),
            };
            key = Some(path);
        } else if let Some(unknown) = backticked(&message, "unknown field `") {
            // The span is the key itself; make sure the path names it.
            if key.as_deref().is_none_or(|k| !k.ends_with(unknown)) {
                key = Some(unknown.to_string());
            }
        }
        SceneError {
            file: self.file.to_string(),
            line,
            key,
            message,
            kind: SceneErrorKind::Invalid,
        }
    }
}

/// The text between `prefix` and the next backtick in `message`, if `message` contains
/// `prefix`.
fn backticked<'m>(message: &'m str, prefix: &str) -> Option<&'m str> {
    let start = message.find(prefix)? + prefix.len();
    let len = message[start..].find('`')?;
    Some(&message[start..start + len])
}
