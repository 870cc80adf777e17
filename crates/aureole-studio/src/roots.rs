//! The folders the studio may read from: a path is resolved (links
//! followed) and refused unless it lies under one of them.

use std::path::{Path, PathBuf};

use crate::error::StudioError;

/// How deep the image list looks under a root, and how many it lists.
const LIST_DEPTH: usize = 4;
const LIST_MAX: usize = 2000;

/// Folders, resolved once.
#[derive(Debug, Clone)]
pub struct Roots(Vec<PathBuf>);

impl Roots {
    /// The folders `dirs`, each of which must exist.
    pub fn new(dirs: &[PathBuf]) -> Result<Roots, StudioError> {
        let mut roots = Vec::new();
        for dir in dirs {
            let resolved = dir
                .canonicalize()
                .map_err(|e| StudioError::BadRequest(format!("--root {}: {e}", dir.display())))?;
            if !resolved.is_dir() {
                return Err(StudioError::BadRequest(format!(
                    "--root {}: is not a folder",
                    dir.display()
                )));
            }
            roots.push(resolved);
        }
        Ok(Roots(roots))
    }

    /// The folders.
    pub fn folders(&self) -> &[PathBuf] {
        &self.0
    }

    /// The file `requested` names (absolute, or relative to a root), once
    /// it is known to lie under a root after following links.
    pub fn resolve(&self, requested: &str) -> Result<PathBuf, StudioError> {
        let path = Path::new(requested);
        let candidates: Vec<PathBuf> = if path.is_absolute() {
            vec![path.to_path_buf()]
        } else {
            self.0.iter().map(|root| root.join(path)).collect()
        };
        let outside = || {
            StudioError::Forbidden(format!(
                "{requested}: is outside the folders the studio may read ({}); start it with --root to add one",
                self.listing()
            ))
        };
        for candidate in &candidates {
            match candidate.canonicalize() {
                Ok(resolved) if self.0.iter().any(|root| resolved.starts_with(root)) => {
                    if !resolved.is_file() {
                        return Err(StudioError::BadRequest(format!(
                            "{requested}: is not a file"
                        )));
                    }
                    return Ok(resolved);
                }
                Ok(_) => return Err(outside()),
                Err(_) => continue,
            }
        }
        // A path that does not exist is still refused first when it points
        // outside, so that the reply does not tell what exists there.
        let lexically_inside = candidates.iter().any(|c| {
            !c.components().any(|p| p == std::path::Component::ParentDir)
                && self.0.iter().any(|root| c.starts_with(root))
        });
        if lexically_inside {
            Err(StudioError::NotFound(format!("{requested}: no such file")))
        } else {
            Err(outside())
        }
    }

    /// The images under the roots, sorted, at most [`LIST_MAX`].
    pub fn images(&self) -> Vec<PathBuf> {
        let mut found = Vec::new();
        for root in &self.0 {
            walk(root, LIST_DEPTH, &mut found);
        }
        found.sort();
        found.dedup();
        found.truncate(LIST_MAX);
        found
    }

    fn listing(&self) -> String {
        self.0
            .iter()
            .map(|r| r.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

fn walk(dir: &Path, depth: usize, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        if name.to_string_lossy().starts_with('.') || found.len() >= LIST_MAX {
            continue;
        }
        let path = entry.path();
        // Symbolic links are not followed here: a link leading out of a
        // root would list what lies outside it.
        let Ok(kind) = entry.file_type() else {
            continue;
        };
        if kind.is_dir() && depth > 0 {
            walk(&path, depth - 1, found);
        } else if kind.is_file() {
            // The image list offers the formats aureole reads, by name.
            if aureole_io::formats::by_extension(&path).is_some() {
                found.push(path);
            }
        }
    }
}
