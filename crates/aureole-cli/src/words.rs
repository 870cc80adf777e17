//! The library's errors in the command line's words: the facts an error
//! carries, with the flag or command that changes them.

use aureole::memory::format_bytes;
use aureole::Error;

/// A library error as the command line says it.
pub fn library(error: &Error) -> String {
    match error {
        Error::Config {
            incomplete_effect: Some(kind),
            ..
        } => match aureole::presets::example_of(kind) {
            Some(preset) => {
                format!("{error}; `aureole presets {preset}` prints a complete {kind} effect")
            }
            None => error.to_string(),
        },
        Error::BadSamples { .. } => format!("{error}; --sanitize replaces them by 0"),
        Error::KernelSize { .. } => {
            format!("{error}; a smaller kernel is (apply --max-kernel WxH, psf --size WxH)")
        }
        Error::Memory {
            needed,
            stage,
            limit,
            fits,
            built,
        } => {
            let hint = match (fits, built) {
                (Some(fit), true) => format!(
                    "--max-kernel {}x{} would need about {} (light then reaches {} px around a source)",
                    fit.kernel.0,
                    fit.kernel.1,
                    format_bytes(fit.bytes),
                    fit.kernel.0 / 2
                ),
                (Some(fit), false) => format!(
                    "a kernel of at most {w}x{h} (aureole psf --size {w}x{h}) would fit",
                    w = fit.kernel.0,
                    h = fit.kernel.1
                ),
                (None, _) => "the image alone is too large for it".to_string(),
            };
            format!(
                "needs about {} (peak while {}) but --max-memory is {}; {hint}, or raise --max-memory",
                format_bytes(*needed),
                stage,
                format_bytes(*limit)
            )
        }
        Error::Allocation { bytes } => format!(
            "could not allocate {} for a plane: the machine's memory is taken by other programs; free some, or lower --max-memory or --max-kernel",
            format_bytes(*bytes)
        ),
        _ => error.to_string(),
    }
}
