//! The one error type of the parser: where (file, line, column) and what went wrong.

use std::fmt;

use crate::model::{SourceName, Span};

/// An error in an HDDL file, or a file that could not be read.
///
/// Displayed on one line as `FILE:LINE:COL: message`. Errors that have no position in the text
/// (the file cannot be read, or is not UTF-8 before any position is known) have `line == 0` and
/// display as `FILE: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    /// The file the error is in.
    pub file: SourceName,
    /// 1-based line, or 0 when the error has no position.
    pub line: u32,
    /// 1-based column in characters (a tab counts as one), or 0 when the error has no position.
    pub col: u32,
    /// What was expected, or what is wrong; one line.
    pub message: String,
}

impl ParseError {
    /// An error at `span` of `file`.
    pub fn new(file: &SourceName, span: Span, message: impl Into<String>) -> Self {
        ParseError {
            file: file.clone(),
            line: span.line,
            col: span.col,
            message: message.into(),
        }
    }

    /// An error about the file as a whole (no position).
    pub fn whole_file(file: &SourceName, message: impl Into<String>) -> Self {
        ParseError {
            file: file.clone(),
            line: 0,
            col: 0,
            message: message.into(),
        }
    }

    /// Where the error is, as a [`Span`].
    pub fn span(&self) -> Span {
        Span {
            line: self.line,
            col: self.col,
        }
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // The message is documented as one line; keep it so even if a name smuggled a newline in.
        let message = crate::text::clip(&self.message);
        if self.line == 0 {
            write!(f, "{}: {}", self.file.display(), message)
        } else {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file.display(),
                self.line,
                self.col,
                message
            )
        }
    }
}

impl std::error::Error for ParseError {}
