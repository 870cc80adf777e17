//! Long work off the GIL: it runs on a thread of its own while the calling
//! thread, which holds the interpreter, wakes every 50 ms to look for
//! Ctrl-C (KeyboardInterrupt) and to report progress; a signal or a
//! failing progress callable cancels the work through the session's
//! token, and the exception is raised once the work has stopped.

use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use aureole::Cancel;
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::prelude::*;

/// How often the waiting thread looks for signals.
const TICK: Duration = Duration::from_millis(50);

/// The latest progress the work reported: its stage in words and the
/// fraction done.
pub type Latest = Arc<Mutex<Option<(&'static str, f64)>>>;

/// Runs `work` on its own thread with the GIL released, stopping it with
/// `cancel` when Python is interrupted or `progress` raises.
pub fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(Latest) -> T + Send,
) -> PyResult<T> {
    let latest: Latest = Arc::new(Mutex::new(None));
    let shared = latest.clone();
    std::thread::scope(|scope| {
        let (sender, mut receiver) = mpsc::sync_channel(1);
        scope.spawn(move || {
            // The receiver is gone only once the caller has stopped waiting.
            let _ = sender.send(work(shared));
        });
        let mut reported = None;
        let mut failure: Option<PyErr> = None;
        loop {
            let (outcome, back) = py.detach(move || (receiver.recv_timeout(TICK), receiver));
            receiver = back;
            match outcome {
                Ok(value) => {
                    return match failure {
                        Some(error) => Err(error),
                        None => {
                            report(progress, &latest, &mut reported)?;
                            Ok(value)
                        }
                    };
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(failure.unwrap_or_else(|| {
                        PyValueError::new_err("aureole: the work stopped without a result")
                    }))
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
            if failure.is_some() {
                continue;
            }
            let checked = py
                .check_signals()
                .and_then(|()| report(progress, &latest, &mut reported));
            if let Err(error) = checked {
                cancel.cancel();
                failure = Some(error);
            }
        }
    })
}

/// Calls `progress(stage, fraction)` when the work has moved on since the
/// last call.
fn report(
    progress: Option<&Bound<'_, PyAny>>,
    latest: &Latest,
    reported: &mut Option<(&'static str, f64)>,
) -> PyResult<()> {
    let Some(progress) = progress else {
        return Ok(());
    };
    let now = *latest
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    if now.is_some() && now != *reported {
        *reported = now;
        if let Some((stage, fraction)) = now {
            progress.call1((stage, fraction))?;
        }
    }
    Ok(())
}

/// The library's one-line message as a Python exception: `ValueError` for
/// what the caller asked, `KeyboardInterrupt` for a cancelled run.
pub fn value_error(error: aureole::Error) -> PyErr {
    match error {
        aureole::Error::Cancelled => PyKeyboardInterrupt::new_err("aureole: interrupted"),
        other => PyValueError::new_err(one_line(&other.to_string())),
    }
}

/// A file's error: `OSError` for what could not be read or written,
/// `ValueError` for what was asked of it (an unknown extension, content
/// the camera refuses).
pub fn file_error(error: aureole_io::Error) -> PyErr {
    use aureole_io::Error as E;
    let message = one_line(&error.to_string());
    match error {
        E::Io { .. } | E::Decode { .. } | E::Encode { .. } | E::Output { .. } => {
            PyOSError::new_err(message)
        }
        E::Content {
            error: aureole::Error::Cancelled,
            ..
        } => PyKeyboardInterrupt::new_err("aureole: interrupted"),
        E::OutputFormat { .. }
        | E::OverwritesInput { .. }
        | E::Content { .. }
        | E::Refused { .. }
        | E::Lens(_)
        | E::Options(_) => PyValueError::new_err(message),
    }
}

/// The message on one line, as the command line prints it.
pub fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}
