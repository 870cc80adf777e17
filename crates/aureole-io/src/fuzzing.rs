//! The entry points the fuzz targets (`fuzz/`) and the corpus replay tests
//! share: each takes arbitrary bytes and must return, never panic, within
//! bounded time and memory.

use crate::limits::Limits;
use crate::read::decode_image;

/// The decoding bound of the load target: large enough for every real
/// format path, small enough that a fuzzer's forged header is refused.
pub const LOAD_LIMIT: Limits = Limits {
    max_bytes: 64 << 20,
};

/// Parses `data` as a config file (UTF-8 or not); the error, if any, must
/// be one line.
pub fn config(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    if let Err(e) = aureole::ConfigFile::parse(&text, "fuzz.toml") {
        assert!(!e.to_string().contains('\n'), "{e}");
    }
}

/// Decodes `data` as PFM.
pub fn pfm(data: &[u8]) {
    if let Ok(pfm) = crate::formats::pfm::decode_limited(data, LOAD_LIMIT.max_bytes) {
        assert_eq!(pfm.planes[0].len(), pfm.width * pfm.height);
    }
}

/// Decodes `data` as any image file we read.
pub fn load(data: &[u8]) {
    match decode_image(data, LOAD_LIMIT) {
        Ok(loaded) => {
            let image = loaded.image;
            for plane in &image.planes {
                assert_eq!(plane.len(), image.width * image.height);
            }
        }
        Err(e) => assert!(!e.contains('\n'), "{e}"),
    }
}
