//! Writing a result: linear formats as they are, display formats through the
//! exposure and tone curve.

use std::path::Path;

use anyhow::anyhow;
use aureole::display::{render, write_picture};
use aureole::io::atomic::folder_of;
use aureole::io::write::{write_linear, LinearOptions};
use aureole::io::{extension, is_display_format, IMAGE_EXTENSIONS};
use aureole::Image;

use crate::display_args::DisplayArgs;
use crate::Failure;

/// Refuses, before any work, an output whose extension we do not write,
/// that would overwrite the input, that is not a plain file, or whose
/// folder is missing or cannot be written.
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
    let folder = folder_of(output);
    if !folder.is_dir() {
        return Err(Failure::Usage(anyhow!(
            "{}: the output folder {} does not exist; create it first",
            output.display(),
            folder.display()
        )));
    }
    // The result replaces a file by renaming over it, which would replace
    // a device or a named pipe by a file.
    if let Ok(meta) = std::fs::metadata(output) {
        if !meta.is_file() {
            return Err(Failure::Usage(anyhow!(
                "{}: exists and is not a plain file (a folder, device or pipe); write to a file",
                output.display()
            )));
        }
    }
    // A folder we cannot write in should fail now, not after the work. The
    // probe is removed before an interruption may exit.
    crate::interrupt::exclusive(|| {
        tempfile::Builder::new()
            .prefix(".aureole-probe-")
            .tempfile_in(folder)
            .map(drop)
    })
    .map_err(|e| {
        Failure::Run(anyhow!(
            "{}: cannot write in the folder {}: {}",
            output.display(),
            folder.display(),
            std::io::Error::from(e.kind())
        ))
    })?;
    Ok(())
}

fn same_file(a: &Path, b: &Path) -> bool {
    let canonical = |p: &Path| Some(folder_of(p).canonicalize().ok()?.join(p.file_name()?));
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
        crate::interrupt::writing(|| write_picture(path, &picture, display.depth(path)))?;
        Ok(Some(format!(
            "white {:.4} cd/m² (EV100 {:.1})",
            picture.white,
            picture.ev100()
        )))
    } else {
        let notes =
            crate::interrupt::writing(|| write_linear(path, image, LinearOptions { half }))?;
        for note in notes {
            if !quiet {
                eprintln!("aureole: note: {}: {note}", path.display());
            }
        }
        Ok(None)
    }
}
