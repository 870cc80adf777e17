//! Typed errors of files: each message is one line that names the file and
//! what is wrong with it.

use std::path::PathBuf;

/// Everything reading and writing files can refuse or fail at.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading or writing a file failed.
    #[error("{path}: {}", aureole::error::describe_io(error))]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying failure (not a `source`: the message already says
        /// it, and a chain would say it twice).
        error: std::io::Error,
    },

    /// A file whose content is not what its format requires.
    #[error("{path}: {message}")]
    Decode {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where.
        message: String,
    },

    /// An encoder (PNG, EXR, plot) failed while writing `path`.
    #[error("{path}: cannot encode {format}: {message}")]
    Encode {
        /// The output file.
        path: PathBuf,
        /// The format being written.
        format: &'static str,
        /// The encoder's message.
        message: String,
    },

    /// An output path whose extension names no format that can hold what
    /// is written there.
    #[error("{path}: unknown output extension {extension:?}; allowed: {allowed}")]
    OutputFormat {
        /// The output path.
        path: PathBuf,
        /// The extension found (empty if none).
        extension: String,
        /// The allowed extensions, in words.
        allowed: String,
    },

    /// An output that is the input itself (by any path or link to it):
    /// writing it would destroy what is being read.
    #[error("{path}: the output would overwrite the input; write to another file")]
    OverwritesInput {
        /// The output path.
        path: PathBuf,
    },

    /// An output path that cannot be used: its folder is missing or
    /// cannot be written, or it names something other than a file.
    #[error("{path}: {reason}")]
    Output {
        /// The output path.
        path: PathBuf,
        /// Why, and what to do.
        reason: String,
    },

    /// A request whose parts cannot go together, or that asks an output
    /// for what its format cannot hold (a glare-only result, whose samples
    /// are negative where light was moved away, into a format without
    /// negative values).
    #[error("{path}: {reason}")]
    Refused {
        /// The output path.
        path: PathBuf,
        /// Why, and what to ask instead.
        reason: String,
    },

    /// Options outside their ranges (a negative threshold, a NaN knee),
    /// in the library's words.
    #[error("{0}")]
    Options(aureole::Error),

    /// A lens file the library refused, in its words (which name the file,
    /// the line and the surface).
    #[error("{0}")]
    Lens(aureole::Error),

    /// What a file holds is refused by the library (a kernel file whose
    /// weights are negative, say).
    #[error("{path}: {error}")]
    Content {
        /// The file.
        path: PathBuf,
        /// The library's reason.
        error: aureole::Error,
    },
}

/// Result with the files' [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub(crate) fn io(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            error,
        }
    }
}
