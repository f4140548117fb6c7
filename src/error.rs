//! The crate's error type. Every input error names the file (or flag), the field path and
//! the offending value; `main` maps input errors to exit status 2 (DESIGN.md §8).

use crate::graph::GraphError;
use std::fmt;
use std::path::PathBuf;

/// Where command-line errors say they come from: the `file` of an error about a flag.
pub const COMMAND_LINE: &str = "command line";

/// Everything that can go wrong in a run.
#[derive(Debug)]
pub enum Error {
    /// A file could not be read. Fatal; input error.
    Read {
        /// The file.
        path: PathBuf,
        /// Why the system refused.
        source: std::io::Error,
    },
    /// A scene or configuration file is not valid JSON, has an unknown field or a value of
    /// the wrong type. `field` is the path to the value (`objects[2].mesh`), or empty when
    /// the JSON does not parse at all. Input error.
    Parse {
        /// The file (or `command line`) the value came from.
        file: String,
        /// The path to the offending value, empty when the JSON does not parse at all.
        field: String,
        /// The parser's message.
        message: String,
    },
    /// A value parsed but is outside what the simulator accepts. Input error.
    Invalid {
        /// The file (or `command line`) the value came from.
        file: String,
        /// The path to the value (`objects[1].transform.scale`) or the flag.
        field: String,
        /// The value as given.
        value: String,
        /// What is accepted instead.
        reason: String,
    },
    /// A mesh file named by a scene could not be loaded or holds bad data. Input error.
    Mesh {
        /// The scene file naming the mesh.
        file: String,
        /// The field that names it.
        field: String,
        /// The mesh or point-cloud file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A patch needs more segments than the stated cap on one scanline interval (DESIGN.md §8):
    /// refused instead of running out of memory or time. Input error.
    SegmentCap {
        /// The lembo's index in the scene.
        lembo: usize,
        /// The scanline whose interval needed more.
        scanline: u32,
        /// The cap on segments per interval.
        cap: usize,
    },
    /// An output file could not be written. Not an input error (exit status 1).
    Write {
        /// The output file.
        path: PathBuf,
        /// Why the system refused.
        source: std::io::Error,
    },
    /// The timed pipeline stopped moving: every unit waits and none holds an item it could
    /// take. `waiting` names each unit and what it waits for. A simulator bug or a
    /// mis-wired graph, not bad input (exit status 1).
    Deadlock {
        /// Each waiting unit and what it waits for.
        waiting: Vec<String>,
    },
    /// A simulator fault (a host thread of the timed model panicked or could not start, or a
    /// merge took items out of order). Exit status 1.
    Internal(String),
    /// The unit graph a timed run was to elaborate is mis-wired (a defect of the graph
    /// description or of a unit's declaration, found before anything runs). Exit status 1.
    Graph(GraphError),
}

impl From<GraphError> for Error {
    fn from(e: GraphError) -> Self {
        Error::Graph(e)
    }
}

impl Error {
    /// Process exit status for this error: 2 for bad input, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Write { .. } | Error::Deadlock { .. } | Error::Internal(_) | Error::Graph(_) => {
                1
            }
            _ => 2,
        }
    }

    /// Shorthand for an [`Error::Invalid`].
    pub fn invalid(
        file: impl Into<String>,
        field: impl Into<String>,
        value: impl fmt::Display,
        reason: impl Into<String>,
    ) -> Error {
        Error::Invalid {
            file: file.into(),
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Read { path, source } => write!(f, "cannot read {}: {source}", path.display()),
            Error::Parse {
                file,
                field,
                message,
            } if field.is_empty() || field == "." => {
                write!(f, "{file}: {message}")
            }
            Error::Parse {
                file,
                field,
                message,
            } => write!(f, "{file}: field `{field}`: {message}"),
            Error::Invalid {
                file,
                field,
                value,
                reason,
            } => {
                write!(f, "{file}: field `{field}` = {value}: {reason}")
            }
            Error::Mesh {
                file,
                field,
                path,
                message,
            } => {
                write!(
                    f,
                    "{file}: field `{field}`: mesh {}: {message}",
                    path.display()
                )
            }
            Error::SegmentCap {
                lembo,
                scanline,
                cap,
            } => write!(
                f,
                "lembo {lembo} needs more than {cap} segments on scanline {scanline}; \
                 refusing it (raise k or fix the patch)"
            ),
            Error::Write { path, source } => write!(f, "cannot write {}: {source}", path.display()),
            Error::Deadlock { waiting } => {
                write!(f, "the timed pipeline deadlocked: {}", waiting.join("; "))
            }
            Error::Internal(what) => write!(f, "internal simulator error: {what}"),
            Error::Graph(e) => write!(
                f,
                "internal simulator error: the unit graph is mis-wired: {e}"
            ),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Read { source, .. } | Error::Write { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// The result of anything that can fail on input or output.
pub type Result<T> = std::result::Result<T, Error>;

/// The largest scene, architecture or sweep-spec file read \[bytes\].
pub const MAX_TEXT_INPUT_BYTES: u64 = 256 << 20;
/// The largest mesh or point-cloud file read \[bytes\].
pub const MAX_DATA_INPUT_BYTES: u64 = 1 << 30;

/// Reads an input file of at most `max` bytes. A larger file, or one that never ends (a
/// device such as `/dev/zero`), is an error, not an out-of-memory.
pub fn read_input(path: &std::path::Path, max: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(max + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("the file is larger than the {max} bytes accepted"),
        ));
    }
    Ok(bytes)
}

/// [`read_input`] as UTF-8 text.
pub fn read_input_string(path: &std::path::Path, max: u64) -> std::io::Result<String> {
    String::from_utf8(read_input(path, max)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

/// A text input file (scene, architecture, sweep spec) of at most
/// [`MAX_TEXT_INPUT_BYTES`]; a failure is an [`Error::Read`] naming the file.
pub fn read_text_file(path: &std::path::Path) -> Result<String> {
    read_input_string(path, MAX_TEXT_INPUT_BYTES).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// The directory `path` is in (`.` for a bare file name), against which the paths a file
/// names are resolved.
pub fn parent_dir(path: &std::path::Path) -> &std::path::Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => std::path::Path::new("."),
    }
}
