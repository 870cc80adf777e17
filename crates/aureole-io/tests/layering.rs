//! aureole-io's modules import each other without circles: the formats
//! sit below reading, writing and kernels, which sit below the one job.

use std::path::Path;

#[path = "../../aureole/tests/modules/mod.rs"]
mod modules;

#[test]
fn the_modules_import_each_other_without_circles() {
    let uses = modules::uses(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    if let Some(circle) = modules::circle(&uses) {
        panic!("import circle: {}", circle.join(" → "));
    }
    assert!(uses.len() > 6, "{uses:?}");
}
