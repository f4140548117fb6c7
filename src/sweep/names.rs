//! The sweep's lowest file: the prefixes and markers of parameter names, the errors every
//! spec field's check builds, and the names of the files the answer writes. Imports nothing
//! of the sweep, so the spec's own types (`spec`) and the answer's settings and sections
//! (`bracket`, `curves`, `sensitivity`, `flips`) can all use it.

use crate::error::Error;

/// The prefix of architecture parameters.
pub(super) const ARCH: &str = "arch.";

/// The prefix of technology parameters.
pub(super) const TECH: &str = "tech.";

/// The parameter that marks a sensitivity variant's point (`arch.rop.count x0.5`).
pub const SENSITIVITY: &str = "sensitivity";

/// A spec value that must be a number, or the error naming its field.
pub(super) fn number(file: &str, field: &str, v: &serde_json::Value) -> Result<f64, Error> {
    v.as_f64().ok_or_else(|| Error::Parse {
        file: file.into(),
        field: field.into(),
        message: format!("expected a number, found {v}"),
    })
}

/// An empty list where one is needed, refused naming its field.
pub(super) fn empty_list(file: &str, field: &str) -> Error {
    Error::invalid(file, field, "[]", "must not be an empty list")
}

/// The same error, said of another file and field (the spec's, for a check written for
/// the command line or an architecture file).
pub(super) fn reword(e: Error, file: &str, field: &str) -> Error {
    match e {
        Error::Invalid { value, reason, .. } => Error::Invalid {
            file: file.into(),
            field: field.into(),
            value,
            reason,
        },
        Error::Parse { message, .. } => Error::Parse {
            file: file.into(),
            field: field.into(),
            message,
        },
        other => other,
    }
}

/// A file the answer writes: its name and bytes.
pub(super) type Figure = (String, Vec<u8>);

/// A scene's name as a file name's part.
pub(super) fn file_stem(scene: &str) -> String {
    scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
