//! The lenses in `crates/aureole/lenses/`, each written from a patent's example:
//! they parse, name their patent and example, and their paraxial focal
//! length and back focus are the patent's within 0.5 %.

use std::path::PathBuf;

use aureole::lens::{Lens, Medium};

fn lenses() -> Vec<(PathBuf, Lens)> {
    let folder = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("lenses");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&folder)
        .expect("crates/aureole/lenses/ is part of the repository")
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).unwrap();
            let lens =
                Lens::parse(&text, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
            (path, lens)
        })
        .collect()
}

#[test]
fn every_shipped_lens_has_its_patents_focal_length_and_back_focus() {
    let lenses = lenses();
    assert!(lenses.len() >= 5, "{}", lenses.len());
    for (path, lens) in &lenses {
        // An anamorphic lens pairs two patents; tests/anamorphic.rs holds
        // its prime to its patent's focal length and its two foci together.
        if lens.is_anamorphic() {
            continue;
        }
        let patent = lens
            .patent
            .as_ref()
            .unwrap_or_else(|| panic!("{}: no [patent]", path.display()));
        assert!(!patent.number.is_empty() && patent.example.starts_with("Example"));
        let p = lens.paraxial().unwrap();
        for (what, stated, ours) in [
            ("focal length", patent.focal_length, p.focal_length),
            ("back focus", patent.back_focus, p.back_focus),
        ] {
            let stated = stated.unwrap_or_else(|| panic!("{}: no {what}", path.display()));
            assert!(
                (ours / stated - 1.0).abs() < 0.005,
                "{}: {what} {ours} against the patent's {stated}",
                path.display()
            );
        }
        // Every glass of a patent has its Abbe number: the ghosts disperse.
        for s in &lens.surfaces {
            if let Medium::Glass { v_d, .. } = s.medium {
                assert!(v_d.is_some(), "{}: a glass without v_d", path.display());
            }
        }
    }
}

#[test]
fn the_shipped_lenses_are_the_kinds_a_photographer_carries() {
    let names: Vec<String> = lenses()
        .iter()
        .map(|(path, _)| path.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    for kind in [
        "double-gauss",
        "retrofocus",
        "telephoto",
        "portrait",
        "zoom",
        "anamorphic",
    ] {
        assert!(
            names.iter().any(|n| n.starts_with(kind)),
            "{kind}: {names:?}"
        );
    }
    // A telephoto is shorter than its focal length, a retrofocus lens
    // reaches farther behind itself than its focal length.
    for (path, lens) in lenses() {
        let p = lens.paraxial().unwrap();
        let length: f64 = lens.surfaces[..lens.surfaces.len() - 1]
            .iter()
            .map(|s| s.thickness)
            .sum::<f64>()
            + p.back_focus;
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        if stem.starts_with("telephoto") {
            assert!(
                length < p.focal_length,
                "{stem}: {length} {}",
                p.focal_length
            );
        }
        if stem.starts_with("retrofocus") {
            assert!(p.back_focus > p.focal_length, "{stem}");
        }
    }
}

/// The first TOML example of docs/lenses.md that holds `holding`.
fn example_of_the_page(holding: &str) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/lenses.md");
    let page = std::fs::read_to_string(path).unwrap();
    page.split("```toml\n")
        .skip(1)
        .filter_map(|rest| rest.split("```").next())
        .find(|block| block.contains(holding))
        .unwrap_or_else(|| panic!("docs/lenses.md has no example with {holding}"))
        .to_string()
}

#[test]
fn the_example_of_docs_lenses_md_is_a_lens_of_its_stated_focal_length() {
    let example = example_of_the_page("[[surface]]");
    let lens = Lens::parse(&example, "docs/lenses.md").unwrap_or_else(|e| panic!("{e}"));
    let p = lens.paraxial().unwrap();
    assert!((p.focal_length * lens.mm_per_unit - 100.0).abs() < 1e-9);
    let stated = lens.patent.as_ref().and_then(|p| p.focal_length).unwrap();
    assert!(
        (p.focal_length / stated - 1.0).abs() < 1e-3,
        "{}",
        p.focal_length
    );
}

#[test]
fn the_camera_of_docs_lenses_md_is_the_preset_with_ghosts() {
    use aureole::{presets, Config, ConfigFile};
    let example = example_of_the_page("type = \"ghosts\"");
    let config = Config::compose([ConfigFile::parse(&example, "docs/lenses.md").unwrap()]);
    let ghosts = config.ghosts.as_ref().unwrap();
    assert_eq!((ghosts.sources, ghosts.threshold), (16, 1000.0));
    assert_eq!(config.effects.len(), 1);
    let preset = presets::find("camera-f8-7blade-ghosts").unwrap();
    assert_eq!(
        Config::compose([preset.config().unwrap()]),
        config,
        "the preset is the page's camera"
    );
}
