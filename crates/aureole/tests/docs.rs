//! The guide's parameter tables (docs/guide.md §2) name exactly the keys
//! each effect and `[camera]` read, so that a parameter added, renamed or
//! removed in the schema is added, renamed or removed there too.

use std::collections::BTreeSet;

use aureole::optics::EFFECT_PARAMETERS;
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
    for (kind, parameters) in EFFECT_PARAMETERS {
        let schema: BTreeSet<String> = parameters.iter().map(|p| p.name.to_string()).collect();
        assert_eq!(keys_of(&sections, kind), schema, "effect {kind}");
    }
    let camera: BTreeSet<String> = CAMERA.iter().map(|p| p.name.to_string()).collect();
    assert_eq!(keys_of(&sections, "[camera]"), camera);
}
