//! The recipe configs in `configs/` (the guide's recipes and the gallery's
//! CandleGlass lens) parse, describe themselves and build kernels that hold
//! all the light: a typo there would break the guide's commands.

use std::path::PathBuf;

use aureole::{Config, ConfigFile, Extent};

fn configs() -> Vec<PathBuf> {
    let folder = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../configs");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&folder)
        .expect("configs/ is part of the repository")
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_recipe_builds_a_kernel_that_sums_to_one() {
    let files = configs();
    assert!(files.len() >= 6, "{files:?}");
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let file =
            ConfigFile::parse(&text, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            file.description.as_deref().is_some_and(|d| !d.is_empty()),
            "{}: no description",
            path.display()
        );
        assert!(!file.effects.is_empty(), "{}: no effect", path.display());
        let mut config = Config::default();
        config.apply(file);
        let kernel = config
            .kernel(&Extent::new(65, 65).unwrap().with_image_width(1000))
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        for channel in 0..kernel.planes().len() {
            let sum = kernel.sum(channel);
            assert!((sum - 1.0).abs() < 1e-5, "{}: ΣK = {sum}", path.display());
        }
    }
}
