//! Reading an input image the way every command does: notes and warnings on
//! stderr, non-finite pixels refused or zeroed, the luminance scale chosen.

use std::path::Path;

use anyhow::anyhow;
use aureole::io::read::{read_image, Loaded};

use crate::Failure;

/// The image and its luminance scale (cd/m² per file unit).
pub struct Input {
    pub loaded: Loaded,
    pub scale: f64,
    /// Where the scale came from, for the summary.
    pub scale_source: &'static str,
}

pub fn read(
    path: &Path,
    input_scale: Option<f64>,
    sanitize: bool,
    quiet: bool,
) -> Result<Input, Failure> {
    let mut loaded = read_image(path)?;
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
    if let Some(bad) = loaded.image.non_finite() {
        if !sanitize {
            return Err(Failure::Run(anyhow!(
                "{}: {} NaN or infinite samples, the first at column {} row {} (from the top); --sanitize replaces them by 0",
                path.display(),
                bad.count,
                bad.first.0,
                bad.first.1
            )));
        }
        let count = loaded.image.sanitize();
        eprintln!(
            "aureole: warning: {}: {count} NaN or infinite samples replaced by 0 (--sanitize)",
            path.display()
        );
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
