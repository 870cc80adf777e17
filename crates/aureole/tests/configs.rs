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
fn every_recipe_builds_a_kernel_that_holds_its_share_of_the_light() {
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
        config.merge(file);
        // Within 32 px of a lamp in a 1000 px frame every recipe keeps
        // most of its light, and within 128 px more of it, never more
        // than all.
        let kernel = |side: usize| {
            config
                .kernel(&Extent::new(side, side).unwrap().with_image_width(1000))
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        };
        let (small, large) = (kernel(65), kernel(257));
        for channel in 0..small.planes().len() {
            let (near, far) = (small.sum(channel), large.sum(channel));
            assert!(
                0.95 < near && near <= far + 1e-6 && far <= 1.0 + 1e-6,
                "{}: ΣK = {near} within 32 px, {far} within 128 px",
                path.display()
            );
        }
    }
}

/// Every preset and recipe, by name, with its parsed file.
fn every_camera() -> Vec<(String, ConfigFile)> {
    let presets = aureole::presets::PRESETS
        .iter()
        .map(|p| (format!("preset {}", p.name), p.config().unwrap()));
    let recipes = configs().into_iter().map(|path| {
        let file = ConfigFile::load(&path).unwrap();
        (path.display().to_string(), file)
    });
    presets.chain(recipes).collect()
}

#[test]
fn every_camera_reads_back_from_its_toml() {
    for (name, file) in every_camera() {
        let text = file.to_toml();
        let again = ConfigFile::parse(&text, &name).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(again, file, "{name}:\n{text}");
    }
}

#[test]
fn defaults_are_left_out_of_the_toml() {
    let file = ConfigFile::parse(
        "[[effect]]\ntype = \"corona\"\nepsilon = 0.01\nrays = 6\nlength = \"20px\"\nwidth = \"3px\"\n\
         [[effect]]\ntype = \"aperture\"\nblades = 7\nspectral = true\nroundness = 0.0\n",
        "chain.toml",
    )
    .unwrap();
    let text = file.to_toml();
    assert!(
        !text.contains("width") && !text.contains("fadeout"),
        "{text}"
    );
    assert!(
        !text.contains("roundness") && !text.contains("spectral"),
        "{text}"
    );
    assert!(
        text.contains("length = \"20px\"") && text.contains("blades = 7"),
        "{text}"
    );
}

#[test]
fn composed_files_read_back_as_the_composed_camera() {
    let cameras = every_camera();
    for pair in cameras.windows(2) {
        let [(_, first), (_, second)] = pair else {
            unreachable!()
        };
        let composed = first.clone().then(second.clone());
        let direct = Config::compose([first.clone(), second.clone()]);
        assert_eq!(Config::compose([composed.clone()]), direct);
        let again = ConfigFile::parse(&composed.to_toml(), "composed").unwrap();
        assert_eq!(Config::compose([again]), direct);
        assert_eq!(composed.description, None);
    }
}
