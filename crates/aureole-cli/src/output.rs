//! Writing a result: linear formats as they are, pictures through the
//! exposure and tone curve; the output path checked before any work.

use std::path::Path;
use std::time::Duration;

use aureole_io::atomic::folder_of;
use aureole_io::formats::Note;
use aureole_io::write::{LinearOptions, WriteOptions, Written};

use crate::display_args::DisplayArgs;
use crate::progress::Progress;
use crate::Failure;

/// Refuses, before any work, an output whose extension we do not write,
/// that would overwrite the input, that is not a plain file, or whose
/// folder is missing or cannot be written ([`aureole_io::job::check_output`];
/// its probe file is removed before an interruption may exit).
pub fn check(output: &Path, input: Option<&Path>) -> Result<(), Failure> {
    crate::interrupt::exclusive(|| aureole_io::job::check_output(output, input))?;
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
            say!(
                "aureole: note: {}: removed {} temporary files older than a day, left by a run that was killed while writing: {}",
                folder.display(),
                removed.len(),
                names.join(", ")
            );
        }
    }
}

/// How a result is written: linear files with `linear`, pictures through
/// the exposure and tone curve `display` asks.
pub fn options(linear: LinearOptions, display: &DisplayArgs) -> WriteOptions {
    WriteOptions {
        linear,
        display: display.options(),
        depth: display.depth(),
    }
}

/// Writes a result to `path` through `write` (given the options: an EXR
/// into a copy of its input, say); returns a description of the display
/// exposure when it made a picture. Notes go out through `progress`.
pub fn write(
    path: &Path,
    linear: LinearOptions,
    display: &DisplayArgs,
    progress: &Progress,
    write: impl FnOnce(&WriteOptions) -> aureole_io::Result<Written>,
) -> Result<Option<String>, Failure> {
    let options = options(linear, display);
    let written = crate::interrupt::writing(|| write(&options))?;
    Ok(said(path, &written, progress))
}

/// What writing `path` made, said: the writer's notes through `progress`
/// (with the flag that keeps what a note says was lost), and a description
/// of the display exposure when it made a picture.
pub fn said(path: &Path, written: &Written, progress: &Progress) -> Option<String> {
    match written {
        Written::Picture { white, ev100 } => {
            Some(format!("white {white:.4} cd/m² (EV100 {ev100:.1})"))
        }
        Written::Linear(notes) => {
            for note in notes {
                let hint = match note {
                    Note::ClampedToHalf { .. } => "; --float keeps them",
                    _ => "",
                };
                progress.note(&format!("aureole: note: {}: {note}{hint}", path.display()));
            }
            None
        }
    }
}
