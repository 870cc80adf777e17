//! Atomic writes: a temporary file in the destination's folder, renamed over
//! the destination only once it is complete, so that an interrupted or
//! failed run leaves no partial file.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{Error, Result};

/// The folder a file `path` is in: its parent, or `.` for a bare name.
pub fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes `path` through `fill`, which gets a buffered writer on a temporary
/// file; the file takes the name `path` only when `fill` succeeded.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut BufWriter<&mut File>) -> Result<()>,
{
    let folder = folder_of(path);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".aureole-").suffix(".part");
    // Temporary files are private by default; the result is an ordinary
    // file, so it gets the ordinary mode (0666 less the umask).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut temp = builder.tempfile_in(folder).map_err(|e| {
        // tempfile names its own temporary path; the user named `path`.
        let error = match e.kind() {
            std::io::ErrorKind::NotFound => std::io::Error::new(
                e.kind(),
                format!("the folder {} does not exist", folder.display()),
            ),
            _ => std::io::Error::from(e.kind()),
        };
        Error::io(path, error)
    })?;
    {
        let mut writer = BufWriter::new(temp.as_file_mut());
        fill(&mut writer)?;
        writer.flush().map_err(|e| Error::io(path, e))?;
    }
    temp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    temp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}
