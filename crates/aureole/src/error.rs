//! Typed errors of the library. Every message is one line that names what was
//! wrong (a parameter, a key, a file), the value found and what is allowed.

use std::path::PathBuf;

use crate::bytes::format_bytes;

/// Everything the library can refuse or fail at.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A physical parameter outside its allowed range.
    #[error("{effect}: {name} = {value} is not allowed: {allowed}")]
    Parameter {
        /// The effect (or section) the parameter belongs to, e.g. `bloom` or `camera`.
        effect: String,
        /// The parameter's name as written in a config file.
        name: &'static str,
        /// The offending value, as the user wrote it.
        value: String,
        /// The allowed range, in words.
        allowed: &'static str,
    },

    /// A length string that is not a number followed by a known unit.
    #[error("length {text:?} is not valid: {reason}; write a number followed by px, um (or µm) or mm, e.g. \"10.4px\" or \"60um\"")]
    LengthSyntax {
        /// What the user wrote.
        text: String,
        /// Why it was refused.
        reason: &'static str,
    },

    /// A physical length (µm, mm) or an angle was asked for without the camera
    /// data that turns it into pixels.
    #[error("{what} needs [camera] {field}: {why}")]
    NeedsCamera {
        /// What asked, e.g. `bloom radius "60um"`.
        what: String,
        /// The missing camera key.
        field: &'static str,
        /// Why that key is needed.
        why: &'static str,
    },

    /// A configuration file (or preset) that does not follow the schema.
    #[error("{source_name}:{line}:{column}: {message}")]
    Config {
        /// The file name, or `preset NAME`.
        source_name: String,
        /// 1-based line of the offending key or value.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong and what is allowed.
        message: String,
        /// The type of an `[[effect]]` that lacks a required field, so that
        /// a front end can point at a complete example of it.
        incomplete_effect: Option<String>,
    },

    /// A lens prescription that cannot be a camera lens, or a surface of
    /// it that breaks the schema.
    #[error("lens {name:?}: {message}")]
    Lens {
        /// The lens's name, or its file.
        name: String,
        /// What is wrong and what is allowed.
        message: String,
    },

    /// A picture's view (projection, field of view) that cannot be used.
    #[error("view {view:?}: {message}")]
    View {
        /// The view as given (Radiance's options, or the config's words).
        view: String,
        /// What is wrong and what is allowed.
        message: String,
    },

    /// A preset name that is not built in.
    #[error("unknown preset {name:?}{}; the presets are: {available}", suggestion.map(|s| format!(" (did you mean {s:?}?)")).unwrap_or_default())]
    UnknownPreset {
        /// The name asked for.
        name: String,
        /// A built-in name close to it.
        suggestion: Option<&'static str>,
        /// The built-in names, comma separated.
        available: String,
    },

    /// A ghosts' lens that is neither shipped nor a lens file.
    #[error("lens = {name:?} is neither a shipped lens{} nor a .toml lens file; the shipped lenses are: {available}", suggestion.map(|s| format!(" (did you mean {s:?}?)")).unwrap_or_default())]
    UnknownLens {
        /// The name asked for.
        name: String,
        /// A shipped name close to it.
        suggestion: Option<&'static str>,
        /// The shipped names, comma separated.
        available: String,
    },

    /// A kernel size that is zero or too large to allocate.
    #[error("kernel size {width}x{height} is not allowed: {allowed}")]
    KernelSize {
        /// Requested width in pixels.
        width: usize,
        /// Requested height in pixels.
        height: usize,
        /// The allowed range.
        allowed: &'static str,
    },

    /// No effect was given, so there is no PSF to build.
    #[error(
        "no effect to build: give at least one [[effect]] (through a preset or a config file)"
    )]
    NoEffect,

    /// A measured PSF that cannot be used.
    #[error("image {file:?}: {why}")]
    MeasuredPsf {
        /// Its file, as the config names it.
        file: String,
        /// What is wrong with it.
        why: String,
    },

    /// A pupil was asked of a chain without an aperture.
    #[error("no pupil to draw: the chain has no [[effect]] type = \"aperture\"")]
    NoAperture,

    /// An image whose size differs from the one a plan was built for.
    #[error("image is {}x{} but the plan was built for {}x{}", found.0, found.1, expected.0, expected.1)]
    SizeMismatch {
        /// The plan's size.
        expected: (usize, usize),
        /// The image's size.
        found: (usize, usize),
    },

    /// Reading a file (a config) failed.
    #[error("{path}: {}", describe_io(error))]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying failure (not a `source`: the message already says
        /// it, and a chain would say it twice).
        error: std::io::Error,
    },

    /// A frame holds samples that are not luminance: NaN or infinite.
    #[error("{count} NaN or infinite samples (luminance must be a finite number), the first at column {} row {} (from the top)", first.0, first.1)]
    BadSamples {
        /// How many samples (over all colour planes).
        count: usize,
        /// Column and row (from the top) of the first.
        first: (usize, usize),
    },

    /// A run would need more memory than its limit.
    #[error("needs about {} (peak while {stage}) but the memory limit is {}{}", format_bytes(*needed), format_bytes(*limit), fits.map(|f| format!("; a kernel of at most {}x{} would need about {}", f.kernel.0, f.kernel.1, format_bytes(f.bytes))).unwrap_or_default())]
    Memory {
        /// The bytes the run would need at its peak.
        needed: u64,
        /// The stage where it peaks, in words.
        stage: &'static str,
        /// The limit, bytes.
        limit: u64,
        /// The largest kernel, halving the extent, that would fit; `None`
        /// when the image alone is too large.
        fits: Option<Fit>,
        /// Whether the kernel is built here (and could be capped) rather
        /// than given ready-made.
        built: bool,
    },

    /// The allocator refused a buffer the run's estimate allowed: the
    /// machine's memory went to other programs meanwhile.
    #[error("could not allocate {} for a plane: the machine's memory is taken by other programs; free some, or lower the memory limit or the kernel's size", format_bytes(*bytes))]
    Allocation {
        /// The bytes asked for.
        bytes: u64,
    },

    /// The GPU was asked for and there is none.
    #[error("no GPU to compute on: {0}; compute on the CPU instead (device cpu or auto)")]
    NoGpu(String),

    /// The GPU refused or failed a step (memory, a lost device).
    #[error("the GPU failed: {0}")]
    Gpu(String),

    /// The caller cancelled the run.
    #[error("cancelled")]
    Cancelled,

    /// An engine was asked to spread light through a kernel it has not
    /// transformed ([`crate::convolve::Engine::prepare`] comes first).
    #[error("the kernel's spectrum is not built: prepare the engine first")]
    NotTransformed,
}

/// A smaller kernel that would fit a memory limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fit {
    /// Its extent, width × height.
    pub kernel: (usize, usize),
    /// The bytes the run would then need.
    pub bytes: u64,
}

/// Result with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// `what` is on the sensor (µm, mm) or needs the pixel pitch, and the
    /// camera has no sensor width.
    pub(crate) fn needs_sensor_width(what: String) -> Self {
        Error::NeedsCamera {
            what,
            field: "sensor_width_mm",
            why: "distances on the sensor become pixels through the pixel pitch, sensor width / image width",
        }
    }

    pub(crate) fn io(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            error,
        }
    }
}

/// The candidate closest to `word` by edit distance, if it is close enough
/// to be a likely typo.
pub(crate) fn closest<'a>(
    word: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (strsim::damerau_levenshtein(word, c), c))
        .filter(|(distance, c)| *distance <= (c.chars().count() / 3).max(1))
        .min_by_key(|(distance, _)| *distance)
        .map(|(_, c)| c)
}

/// An I/O failure in a user's words, without the OS error number: for
/// every front end's messages about files.
pub fn describe_io(error: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    let words = match error.kind() {
        _ if error.raw_os_error().is_none() => return error.to_string(),
        K::NotFound => "no such file or folder",
        K::PermissionDenied => "permission denied",
        K::IsADirectory => "is a folder, not a file",
        K::NotADirectory => "a folder on the path is a file",
        K::StorageFull => "no space left on the device",
        K::FileTooLarge => "the file exceeds the size this system allows",
        K::ReadOnlyFilesystem => "the file system is read-only",
        _ => {
            let text = error.to_string();
            return match text.find(" (os error") {
                Some(at) => text[..at].to_string(),
                None => text,
            };
        }
    };
    words.to_string()
}
