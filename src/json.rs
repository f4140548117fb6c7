//! Strict JSON parsing for every input file (scenes, architectures, technology files, sweep
//! specs): unknown trailing text is an error, and a serde error names the file and the
//! field path where it happened (DESIGN.md §8), tracked by `serde_path_to_error`. A leaf:
//! the input formats import it, it imports only the errors.

use crate::error::{Error, Result};

/// Parses JSON text into `T`: errors name the file and the field path, and text after the
/// value is an error, not ignored.
pub(crate) fn parse_strict<T: serde::de::DeserializeOwned>(text: &str, file: &str) -> Result<T> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let value: T = serde_path_to_error::deserialize(&mut *de).map_err(|e| parse_error(file, e))?;
    de.end().map_err(|e| Error::Parse {
        file: file.to_string(),
        field: String::new(),
        message: e.to_string(),
    })?;
    Ok(value)
}

fn parse_error(file: &str, e: serde_path_to_error::Error<serde_json::Error>) -> Error {
    // A syntax error leaves an unknown (`?`) last segment, and one before any field an
    // empty path (printed "."): drop both, serde's message gives the line and column.
    let mut field = e.path().to_string();
    while field.ends_with('?') {
        field.pop();
        if field.ends_with('.') {
            field.pop();
        }
    }
    if field == "." {
        field.clear();
    }
    Error::Parse {
        file: file.to_string(),
        field,
        message: e.into_inner().to_string(),
    }
}

/// Sets the field at `path` (dotted) of `what`'s JSON (`architecture`, `technology`); the
/// field must exist and not be a group of fields. The error says which part is unknown and
/// what is there. A sweep's `arch.`/`tech.` parameters and `render --set` use it.
pub(crate) fn set_field(
    root: &mut serde_json::Value,
    path: &str,
    v: serde_json::Value,
    what: &str,
) -> std::result::Result<(), String> {
    use serde_json::Value;
    let parts: Vec<&str> = path.split('.').collect();
    let mut at = root;
    for (i, part) in parts.iter().enumerate() {
        let here = parts[..i].join(".");
        let Value::Object(map) = at else {
            return Err(format!(
                "unknown {what} field `{path}`: `{here}` has no fields"
            ));
        };
        if !map.contains_key(*part) {
            let known: Vec<&str> = map.keys().map(String::as_str).collect();
            return Err(format!(
                "unknown {what} field `{path}`; {} has: {}",
                if here.is_empty() {
                    format!("the {what}")
                } else {
                    format!("`{here}`")
                },
                known.join(", ")
            ));
        }
        at = map.get_mut(*part).expect("checked");
    }
    if let Value::Object(map) = at {
        let known: Vec<&str> = map.keys().map(String::as_str).collect();
        return Err(format!(
            "`{path}` is a group of fields; name one of them: {}",
            known.join(", ")
        ));
    }
    *at = v;
    Ok(())
}

/// The value at `path` (dotted) of a JSON object, if there is one.
pub(crate) fn field_at<'a>(
    root: &'a serde_json::Value,
    path: &str,
) -> Option<&'a serde_json::Value> {
    path.split('.').try_fold(root, |at, part| at.get(part))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Outer {
        inner: Vec<Inner>,
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Inner {
        width: u32,
    }

    fn parse_field(text: &str) -> (String, String) {
        match parse_strict::<Outer>(text, "f.json") {
            Err(Error::Parse {
                file,
                field,
                message,
            }) => {
                assert_eq!(file, "f.json");
                (field, message)
            }
            other => panic!("{text} gave {other:?}"),
        }
    }

    #[test]
    fn errors_name_the_field_path_and_trailing_text_is_refused() {
        let ok: Outer = parse_strict(r#"{"inner": [{"width": 3}]}"#, "f.json").unwrap();
        assert_eq!(ok.inner[0].width, 3);
        let (field, message) = parse_field(r#"{"inner": [{"width": 3}, {"width": "x"}]}"#);
        assert_eq!(field, "inner[1].width");
        assert!(message.contains("invalid type"), "{message}");
        let (field, message) = parse_field(r#"{"inner": [{"height": 3}]}"#);
        assert_eq!(field, "inner[0].height");
        assert!(message.contains("unknown field"), "{message}");
        // A syntax error before any field, or text after the value: no path, serde's message
        // gives the line and column.
        let (field, message) = parse_field("{,}");
        assert_eq!(field, "");
        assert!(message.contains("line 1 column 2"), "{message}");
        let (field, message) = parse_field(r#"{"inner": []} {}"#);
        assert_eq!(field, "");
        assert!(message.contains("trailing characters"), "{message}");
    }
}
