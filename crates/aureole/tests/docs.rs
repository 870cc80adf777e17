//! The guide's parameter tables (docs/guide.md §2) name exactly the keys
//! each effect and `[camera]` read, so that a parameter added, renamed or
//! removed in the schema is added, renamed or removed there too.

use std::collections::BTreeSet;

use aureole::config::effect_kinds;
use aureole::schema::CAMERA;

/// The keys in the first column of each section's table, by the name in
/// the section's heading (`bloom`, `[camera]`); nested tables
/// (`[[effect.filter]]`) left out.
fn documented() -> Vec<(String, BTreeSet<String>)> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/guide.md");
    let guide = std::fs::read_to_string(path).expect("docs/guide.md is part of the repository");
    let mut sections: Vec<(String, BTreeSet<String>)> = Vec::new();
    for line in guide.lines() {
        if line.starts_with('#') {
            let name = line.strip_prefix("### `").and_then(|h| h.split('`').next());
            sections.push((name.unwrap_or_default().to_string(), BTreeSet::new()));
        } else if let (Some(first), Some((_, keys))) =
            (line.strip_prefix("| `"), sections.last_mut())
        {
            if first.starts_with("[[") {
                continue;
            }
            let cell = format!("`{}", first.split(" |").next().unwrap_or_default());
            keys.extend(cell.split('`').skip(1).step_by(2).map(str::to_string));
        }
    }
    sections
}

fn keys_of(sections: &[(String, BTreeSet<String>)], name: &str) -> BTreeSet<String> {
    let found = sections.iter().find(|(section, _)| section == name);
    found
        .unwrap_or_else(|| panic!("docs/guide.md has no section \"### `{name}`\""))
        .1
        .clone()
}

#[test]
fn the_guide_documents_every_parameter_of_every_effect() {
    let sections = documented();
    for (kind, parameters) in effect_kinds() {
        let schema: BTreeSet<String> = parameters.iter().map(|p| p.name.to_string()).collect();
        assert_eq!(keys_of(&sections, kind), schema, "effect {kind}");
    }
    let camera: BTreeSet<String> = CAMERA.iter().map(|p| p.name.to_string()).collect();
    assert_eq!(keys_of(&sections, "[camera]"), camera);
}

/// The README and every page under docs/, by path.
fn pages() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut pages = vec![root.join("README.md")];
    for entry in std::fs::read_dir(root.join("docs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") {
            pages.push(path);
        }
    }
    pages
}

#[test]
fn every_link_between_the_pages_leads_to_a_file() {
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        let folder = page.parent().unwrap();
        for link in text.split("](").skip(1) {
            let target = link.split([')', ' ']).next().unwrap_or_default();
            let path = target.split('#').next().unwrap_or_default();
            if path.is_empty() || path.contains("://") || path.starts_with("mailto:") {
                continue;
            }
            assert!(
                folder.join(path).exists(),
                "{}: the link to {target} leads nowhere",
                page.display()
            );
        }
    }
}

#[test]
fn the_readme_is_read_in_five_minutes() {
    let readme = &pages()[0];
    let lines = std::fs::read_to_string(readme).unwrap().lines().count();
    assert!(
        lines <= 200,
        "README.md has {lines} lines; the rest belongs in docs/"
    );
}
