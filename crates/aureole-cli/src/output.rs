//! Writing a result: linear formats as they are, pictures through the
//! exposure and tone curve; the output path checked before any work.

use std::path::Path;
use std::time::Duration;

use anyhow::anyhow;
use aureole::Image;
use aureole_io::atomic::folder_of;
use aureole_io::formats::{Note, Original};
use aureole_io::write::{
    output_format, refuse_overwrite, write_image_into, LinearOptions, WriteOptions, Written,
};

use crate::display_args::DisplayArgs;
use crate::progress::Progress;
use crate::Failure;

/// Refuses, before any work, an output whose extension we do not write,
/// that would overwrite the input, that is not a plain file, or whose
/// folder is missing or cannot be written.
pub fn check(output: &Path, input: Option<&Path>) -> Result<(), Failure> {
    output_format(output)?;
    if let Some(input) = input {
        refuse_overwrite(output, input)?;
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
        // An output path that cannot be used is the user's to change: 2.
        Failure::Usage(anyhow!(
            "{}: cannot write in the folder {}: {}",
            output.display(),
            folder.display(),
            std::io::Error::from(e.kind())
        ))
    })?;
    Ok(())
}

/// Removes what runs killed while writing left in the output folders
/// (temporary files older than a day), with a note.
pub fn tidy<'a>(outputs: impl IntoIterator<Item = &'a Path>, quiet: bool) {
    let mut folders: Vec<&Path> = outputs.into_iter().map(folder_of).collect();
    folders.sort();
    folders.dedup();
    for folder in folders {
        let removed = aureole_io::atomic::remove_stale(folder, Duration::from_secs(24 * 3600));
        if !removed.is_empty() && !quiet {
            let names: Vec<String> = removed
                .iter()
                .filter_map(|p| p.file_name())
                .map(|n| n.to_string_lossy().into_owned())
                .collect();
            eprintln!(
                "aureole: note: {}: removed {} temporary files older than a day, left by a run that was killed while writing: {}",
                folder.display(),
                removed.len(),
                names.join(", ")
            );
        }
    }
}

/// Writes `image` (`scale` cd/m² per unit) to `path`, an EXR into the
/// `original` it was read from; returns a description of the display
/// exposure when it made a picture. Notes go out through `progress`.
pub fn write(
    path: &Path,
    image: &Image,
    scale: f64,
    (linear, original): (LinearOptions, Original),
    display: &DisplayArgs,
    progress: &Progress,
) -> Result<Option<String>, Failure> {
    let options = WriteOptions {
        linear,
        display: display.options(),
        depth: display.depth(),
    };
    match crate::interrupt::writing(|| write_image_into(path, image, scale, &options, original))? {
        Written::Picture { white, ev100 } => {
            Ok(Some(format!("white {white:.4} cd/m² (EV100 {ev100:.1})")))
        }
        Written::Linear(notes) => {
            for note in notes {
                let hint = match note {
                    Note::ClampedToHalf { .. } => "; --float keeps them",
                    _ => "",
                };
                progress.note(&format!("aureole: note: {}: {note}{hint}", path.display()));
            }
            Ok(None)
        }
    }
}
