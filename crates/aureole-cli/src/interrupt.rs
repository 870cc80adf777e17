//! Ctrl-C (and SIGTERM from a render farm's scheduler) stops a run at once
//! without leaving a partial file: a write in progress is let finish first.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Held while a file is written: the handler waits for it before exiting.
static WRITING: Mutex<()> = Mutex::new(());
/// Outputs completed, for the message on interruption.
static WRITTEN: AtomicUsize = AtomicUsize::new(0);

/// The exit status of a run stopped by a signal (128 + SIGINT).
const INTERRUPTED: i32 = 130;

/// Installs the handler; a failure to install it only loses the clean stop.
pub fn install() {
    let installed = ctrlc::set_handler(|| {
        let _writing = WRITING.lock().unwrap_or_else(|p| p.into_inner());
        let written = WRITTEN.load(Ordering::SeqCst);
        say!(
            "aureole: interrupted: stopped with {written} output(s) written whole; no partial file is left"
        );
        std::process::exit(INTERRUPTED);
    });
    if let Err(e) = installed {
        say!("aureole: warning: cannot handle Ctrl-C ({e}); an interrupted write may leave a .part file");
    }
}

/// Runs `work` (which touches files) so that an interruption waits for it
/// to finish.
pub fn exclusive<T>(work: impl FnOnce() -> T) -> T {
    let _writing = WRITING.lock().unwrap_or_else(|p| p.into_inner());
    work()
}

/// Writes an output through `write`, exclusively; counts it when it is
/// complete.
pub fn writing<T, E>(write: impl FnOnce() -> Result<T, E>) -> Result<T, E> {
    exclusive(|| {
        let result = write();
        if result.is_ok() {
            WRITTEN.fetch_add(1, Ordering::SeqCst);
        }
        result
    })
}
