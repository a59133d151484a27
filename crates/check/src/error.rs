//! Bad input: every way a plan file can fail to be read, with where it failed.

use thiserror::Error;

/// Why a plan file could not be checked (the CLI maps every variant to exit code 3).
#[derive(Debug, Error)]
pub enum InputError {
    /// The file could not be read.
    #[error("cannot read {file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// The file is not JSON.
    #[error("{file}: not valid JSON at line {line}, column {column}: {message}")]
    Syntax {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// A key the format requires is absent.
    #[error("missing key `{path}`")]
    Missing { path: String },
    /// A value has the wrong type or an impossible value (unknown name, NaN, empty shape...).
    #[error("bad value at `{path}`: {message}")]
    Bad { path: String, message: String },
}

impl InputError {
    /// A [`InputError::Bad`] at `path`.
    pub fn bad(path: &str, message: impl Into<String>) -> Self {
        InputError::Bad {
            path: path.to_string(),
            message: message.into(),
        }
    }
}
