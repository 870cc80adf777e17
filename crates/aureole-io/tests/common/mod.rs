//! What the EXR tests share. Each test binary compiles this module and
//! uses a part of it, hence the allowance below.
#![allow(dead_code)]

#[path = "../../../../tests/support/required.rs"]
pub mod required;
use std::path::{Path, PathBuf};

use exr::prelude::*;

/// OpenEXR's sample set beside the repository; `None` (said) where it is
/// absent, so that `cargo test` passes from a clean clone.
pub fn images() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/openexr-images");
    if dir.is_dir() {
        Some(dir)
    } else {
        required::missing("openexr-images", &format!("{} is absent", dir.display()));
        None
    }
}

/// Every part, layer, channel and attribute of a file as the `exr` crate
/// reads it: the independent decoder the tests compare with.
pub fn read_all(path: &Path) -> FlatImage {
    read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
