//! PFM bytes → an image or one error line.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aureole_io::fuzzing::pfm(data);
});
