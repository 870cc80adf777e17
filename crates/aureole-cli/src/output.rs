//! Writing a result: linear formats as they are, display formats through the
//! exposure and tone curve.

use std::path::Path;

use anyhow::anyhow;
use aureole::display::{render, write_picture};
use aureole::io::write::{write_linear, LinearOptions};
use aureole::io::{extension, is_display_format, IMAGE_EXTENSIONS};
use aureole::Image;

use crate::display_args::DisplayArgs;
use crate::Failure;

/// Refuses, before any work, an output whose extension we do not write or
/// that would overwrite the input.
pub fn check(output: &Path, input: Option<&Path>) -> Result<(), Failure> {
    let known =
        matches!(extension(output).as_str(), "exr" | "hdr" | "pfm") || is_display_format(output);
    if !known {
        return Err(aureole::Error::OutputFormat {
            path: output.to_path_buf(),
            extension: extension(output),
            allowed: IMAGE_EXTENSIONS,
        }
        .into());
    }
    if let Some(input) = input {
        if same_file(input, output) {
            return Err(Failure::Usage(anyhow!(
                "{}: the output would overwrite the input; write to another file",
                output.display()
            )));
        }
    }
    Ok(())
}

fn same_file(a: &Path, b: &Path) -> bool {
    let canonical = |p: &Path| {
        let file = p.file_name()?;
        let parent = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Some(parent.canonicalize().ok()?.join(file))
    };
    match (canonical(a), canonical(b)) {
        (Some(a), Some(b)) => a == b,
        _ => false,
    }
}

/// Writes `image` to `path`; returns a description of the display exposure
/// when it made a picture.
pub fn write(
    path: &Path,
    image: &Image,
    scale: f64,
    display: &DisplayArgs,
    half: bool,
    quiet: bool,
) -> Result<Option<String>, Failure> {
    if is_display_format(path) {
        let picture = render(image, scale, &display.options());
        write_picture(path, &picture, display.depth(path))?;
        Ok(Some(format!(
            "white {:.4} cd/m² (EV100 {:.1})",
            picture.white,
            picture.ev100()
        )))
    } else {
        for note in write_linear(path, image, LinearOptions { half })? {
            if !quiet {
                eprintln!("aureole: note: {}: {note}", path.display());
            }
        }
        Ok(None)
    }
}
