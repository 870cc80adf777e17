//! Reading an input image the way every command does: the file's notes on
//! stderr, the frame made by the library (bad samples refused or zeroed,
//! the luminance scale chosen), and what it decided said.

use std::path::Path;

use aureole::{FrameOptions, ScaleSource};
use aureole_io::job::{Input, Job};
use aureole_io::limits::Limits;
use aureole_io::read::{Choice, Loaded};
use aureole_io::spares::Spares;

use crate::values::parse_positive;
use crate::Failure;

/// Which light of a file to read, and its scale: the flags `apply` and
/// `info` share.
#[derive(clap::Args)]
pub struct SourceArgs {
    /// cd/m² per file unit. Default: the EXR whiteLuminance attribute if the
    /// file has one, else 1 (the file holds cd/m²).
    #[arg(long, value_name = "X", value_parser = parse_positive)]
    pub input_scale: Option<f64>,

    /// The layer of a multi-layer EXR, by its name (the channel prefix:
    /// ViewLayer.Combined for ViewLayer.Combined.R …). Default: the
    /// unprefixed R, G, B, else the only colour layer, else Blender's
    /// Combined. The other layers go back into an EXR output unchanged.
    #[arg(long, value_name = "NAME")]
    pub layer: Option<String>,

    /// The part of a multi-part EXR to read the layer from, by index (from
    /// 0) or name.
    #[arg(long, value_name = "PART")]
    pub part: Option<String>,
}

impl SourceArgs {
    /// The layer and part chosen.
    pub fn choice(&self) -> Choice {
        Choice {
            layer: self.layer.clone(),
            part: self.part.clone(),
        }
    }
}

/// Decodes the input of `job` as a frame ([`Job::decode`], into the
/// buffers `spares` lends), saying what the user should know about it and
/// the luminance scale it takes; with the rest of the file, for writing
/// the result back into it.
pub fn read(job: &Job, limits: Limits, spares: &Spares, quiet: bool) -> Result<Input, Failure> {
    let path = job.file();
    let mut input = job.decode(limits, spares).map_err(|e| failure(path, e))?;
    say_read(path, &mut input, quiet);
    if !quiet {
        say!(
            "aureole: note: {}: luminance scale {} cd/m² per unit ({})",
            path.display(),
            input.frame.scale(),
            scale_source(input.frame.scale_source())
        );
    }
    Ok(input)
}

/// A file read from `path` as a frame, with its notes and warnings said
/// ([`say_read`]).
pub fn read_loaded(
    path: &Path,
    loaded: Loaded,
    options: &FrameOptions,
    quiet: bool,
) -> Result<Input, Failure> {
    let mut input = aureole_io::job::input(path, loaded, options).map_err(|e| failure(path, e))?;
    say_read(path, &mut input, quiet);
    Ok(input)
}

/// Says what the user should know of a file read from `path`: the
/// reader's notes (taken from `input`, said once), a display image's
/// relative luminance, samples passed or zeroed.
fn say_read(path: &Path, input: &mut Input, quiet: bool) {
    let note = |text: &str| {
        if !quiet {
            say!("aureole: note: {}: {text}", path.display());
        }
    };
    for text in std::mem::take(&mut input.notes) {
        note(&text);
    }
    if input.display_referred {
        say!(
            "aureole: warning: {}: an 8/16-bit {} is a display image: decoded from sRGB to linear, its luminance is only relative (set --input-scale for cd/m²)",
            path.display(),
            input.format
        );
    }
    let frame = &input.frame;
    if frame.negatives() > 0 {
        note(&format!(
            "{} negative samples passed through as they are (--sanitize makes them 0)",
            frame.negatives()
        ));
    }
    if frame.replaced() > 0 {
        say!(
            "aureole: warning: {}: {} NaN, infinite or negative samples replaced by 0 (--sanitize)",
            path.display(),
            frame.replaced()
        );
    }
}

/// Where the scale came from, in the command line's words.
pub fn scale_source(source: ScaleSource) -> &'static str {
    match source {
        ScaleSource::Given => "--input-scale",
        ScaleSource::WhiteLuminance => "the file's whiteLuminance",
        ScaleSource::Default => "default: file units are cd/m²",
    }
}

/// A library error about the image at `path`: what its samples hold or
/// what it would need (memory, a kernel for its size) is said with the
/// file's name, as a failure of the run on that file.
pub fn about(path: &Path, error: aureole::Error) -> Failure {
    use aureole::Error as E;
    match error {
        E::BadSamples { .. } | E::Memory { .. } | E::KernelSize { .. } => Failure::Run(
            anyhow::anyhow!(crate::words::library(&error)).context(path.display().to_string()),
        ),
        _ => Failure::from(error),
    }
}

/// An error of the one job on the file at `path`: the library's refusal of
/// what it holds as [`about`] says it, the file's own as the files' errors.
pub fn failure(path: &Path, error: aureole_io::Error) -> Failure {
    match error {
        aureole_io::Error::Content { error, .. } => about(path, error),
        other => Failure::from(other),
    }
}
