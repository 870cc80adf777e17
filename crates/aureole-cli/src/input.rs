//! Reading an input image the way every command does: notes and warnings on
//! stderr, non-finite pixels refused or zeroed, the luminance scale chosen.

use std::path::Path;

use anyhow::anyhow;
use aureole::io::read::{read_image_limited, Limits, Loaded};

use crate::Failure;

/// The image and its luminance scale (cd/m² per file unit).
pub struct Input {
    pub loaded: Loaded,
    pub scale: f64,
    /// Where the scale came from, for the summary.
    pub scale_source: &'static str,
}

/// How to read: the scale, what to do with samples that are not luminance,
/// the decoder's memory bound.
pub struct Options {
    pub input_scale: Option<f64>,
    /// Replace NaN, infinite and negative samples by 0.
    pub sanitize: bool,
    /// Let negative samples through (they never pass a threshold).
    pub keep_negative: bool,
    pub limits: Limits,
    pub quiet: bool,
}

pub fn read(path: &Path, options: &Options) -> Result<Input, Failure> {
    let (input_scale, sanitize, quiet) = (options.input_scale, options.sanitize, options.quiet);
    let mut loaded = read_image_limited(path, options.limits)?;
    let note = |text: &str| {
        if !quiet {
            eprintln!("aureole: note: {}: {text}", path.display());
        }
    };
    for text in &loaded.notes {
        note(text);
    }
    if loaded.display_referred {
        eprintln!(
            "aureole: warning: {}: an 8/16-bit {} is a display image: decoded from sRGB to linear, its luminance is only relative (set --input-scale for cd/m²)",
            path.display(),
            loaded.format
        );
    }
    let negatives = if options.keep_negative {
        None
    } else {
        loaded.image.negatives()
    };
    let refused = [
        (loaded.image.non_finite(), "NaN or infinite", ""),
        (negatives, "negative", ", --keep-negative keeps them"),
    ];
    for (found, what, keep) in refused {
        if let (Some(bad), false) = (found, sanitize) {
            return Err(Failure::Run(anyhow!(
                "{}: {} {what} samples (luminance must be a finite number of at least 0), the first at column {} row {} (from the top); --sanitize replaces them by 0{keep}",
                path.display(),
                bad.count,
                bad.first.0,
                bad.first.1
            )));
        }
    }
    if sanitize {
        let count = loaded.image.sanitize(!options.keep_negative);
        if count > 0 {
            eprintln!(
                "aureole: warning: {}: {count} NaN, infinite or negative samples replaced by 0 (--sanitize)",
                path.display()
            );
        }
    }
    let (scale, scale_source) = match (input_scale, loaded.image.white_luminance) {
        (Some(scale), _) => (scale, "--input-scale"),
        (None, Some(white)) => (f64::from(white), "the file's whiteLuminance"),
        (None, None) => (1.0, "default: file units are cd/m²"),
    };
    Ok(Input {
        loaded,
        scale,
        scale_source,
    })
}
