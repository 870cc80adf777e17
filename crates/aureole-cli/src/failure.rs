//! How a run fails, for the exit status: what the user asked is wrong
//! (2), or the work itself failed (1); the library's errors sorted into
//! the one or the other, in the command line's words.

use crate::words;

/// How a run failed: a usage or configuration error (exit 2) or a failure
/// while running (exit 1).
pub enum Failure {
    Usage(anyhow::Error),
    Run(anyhow::Error),
}

/// Sorts a library error: what the user wrote is wrong (2), or the work
/// itself failed (1); the words are the command line's (flags, commands).
impl From<aureole::Error> for Failure {
    fn from(error: aureole::Error) -> Self {
        use aureole::Error as E;
        match error {
            E::Io { .. } | E::BadSamples { .. } | E::Memory { .. } | E::Cancelled => {
                Failure::Run(anyhow::anyhow!(words::library(&error)))
            }
            _ => Failure::Usage(anyhow::anyhow!(words::library(&error))),
        }
    }
}

impl From<aureole_io::Error> for Failure {
    fn from(error: aureole_io::Error) -> Self {
        use aureole_io::Error as E;
        match error {
            E::Io { .. } | E::Encode { .. } | E::Decode { .. } => Failure::Run(error.into()),
            E::Content { .. }
            | E::OutputFormat { .. }
            | E::OverwritesInput { .. }
            | E::Output { .. }
            | E::Refused { .. }
            | E::Lens(_)
            | E::Options(_) => Failure::Usage(error.into()),
        }
    }
}
