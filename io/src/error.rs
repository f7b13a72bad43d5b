//! The errors of `flatray-io`: each names the file, and for scene errors
//! the line and column, and says what was expected.

use std::path::PathBuf;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file itself could not be read.
    #[error("{}: cannot read the scene file: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is a plan for `flatray import` (an SVG drawing, a Tiled
    /// map, an image), not a scene.
    #[error(
        "{}: this is {what}, not a scene file; `flatray import` turns it into one: flatray import {} -o {}.ron",
        path.display(), path.display(), path.file_stem().map_or("plan".into(), |s| s.to_string_lossy())
    )]
    NotAScene { path: PathBuf, what: &'static str },
    /// The text is not a valid scene: syntax, unknown field, wrong type,
    /// or a value out of range.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Invalid {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// Scene values given in code (`name` names them) are not a valid
    /// scene: `at` is the path of the value, as `lights[2].Spot.cone`
    /// (empty for the whole), and `message` says what was expected.
    #[error("{name}: {}{message}", if at.is_empty() { String::new() } else { format!("{at}: ") })]
    Value {
        name: String,
        at: String,
        message: String,
    },
}

impl SceneError {
    /// The (line, column) the error points at, when it points anywhere.
    pub fn location(&self) -> Option<(usize, usize)> {
        match self {
            SceneError::Read { .. } | SceneError::NotAScene { .. } | SceneError::Value { .. } => {
                None
            }
            SceneError::Invalid { line, column, .. } => Some((*line, *column)),
        }
    }
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{}: unknown output format: expected a name ending in .png or .exr", path.display())]
    UnknownFormat { path: PathBuf },
    #[error("{}: cannot write the image: {message}", path.display())]
    Io { path: PathBuf, message: String },
}
