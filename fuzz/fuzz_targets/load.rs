//! Any file's bytes → an image (EXR, Radiance, PFM, PNG, JPEG, TIFF) or one
//! error line, under a memory bound.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aureole_io::fuzzing::load(data);
});
