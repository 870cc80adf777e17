//! Built-in presets: TOML files compiled into the library, each a config
//! file a user can print and start from.

use crate::config::ConfigFile;
use crate::error::{Error, Result};

/// A built-in preset.
#[derive(Debug, Clone, Copy)]
pub struct Preset {
    /// Its name, as given to `--preset`.
    pub name: &'static str,
    /// Its TOML text.
    pub toml: &'static str,
}

macro_rules! presets {
    ($($name:literal),* $(,)?) => {
        &[$(Preset { name: $name, toml: include_str!(concat!("../presets/", $name, ".toml")) }),*]
    };
}

/// The camera `apply` and `demo` use when no preset or config is given.
pub const DEFAULT_PRESET: &str = "paper-fig5-both";

/// Every built-in preset, in the order they are listed.
pub const PRESETS: &[Preset] = presets!(
    "paper-fig4-bloom",
    "paper-fig5-corona",
    "paper-fig5-both",
    "paper-fig6a",
    "paper-fig6b",
    "paper-fig6c",
    "paper-fig6d",
    "human-eye-vos",
    "human-eye-cie-25",
    "human-eye-cie-70",
    "camera-f8-7blade",
    "camera-f8-7blade-ghosts",
    "camera-f11-6blade",
    "camera-f16-9blade",
    "star-filter-4pt",
    "star-filter-6pt",
    "star-filter-8pt",
    "film-35mm-no-remjet",
    "film-35mm-remjet",
);

impl Preset {
    /// The preset's parsed configuration.
    pub fn config(&self) -> Result<ConfigFile> {
        ConfigFile::parse(self.toml, &format!("preset {}", self.name))
    }

    /// Its one-line description.
    pub fn description(&self) -> String {
        self.config()
            .ok()
            .and_then(|c| c.description)
            .unwrap_or_default()
    }
}

/// The preset called `name`, or an error listing them all.
pub fn find(name: &str) -> Result<&'static Preset> {
    PRESETS
        .iter()
        .find(|p| p.name == name)
        .ok_or_else(|| Error::UnknownPreset {
            name: name.to_string(),
            suggestion: crate::error::closest(name, PRESETS.iter().map(|p| p.name)),
            available: PRESETS
                .iter()
                .map(|p| p.name)
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// A built-in preset with a complete effect of type `kind` (`bloom`,
/// `corona`, `vos`, `aperture`, `ghosts`), to point a user at.
pub fn example_of(kind: &str) -> Option<&'static str> {
    PRESETS
        .iter()
        .find(|p| p.config().is_ok_and(|c| c.kinds().any(|k| k == kind)))
        .map(|p| p.name)
}

/// The `[[effect]]` table of type `kind` in its example preset
/// ([`example_of`]), as the preset writes it: what a front end's panel
/// for the effect starts from.
pub fn example_table(kind: &str) -> Option<toml::Table> {
    let preset = find(example_of(kind)?).ok()?;
    let table: toml::Table = toml::from_str(preset.toml).ok()?;
    let effects = table.get("effect")?.as_array()?;
    effects
        .iter()
        .filter_map(toml::Value::as_table)
        .find(|t| t.get("type").and_then(toml::Value::as_str) == Some(kind))
        .cloned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_parses_and_has_a_description() {
        for preset in PRESETS {
            let config = preset.config().unwrap();
            assert!(!config.effects.is_empty(), "{}", preset.name);
            let description = preset.description();
            assert!(
                !description.is_empty() && !description.contains('\n'),
                "{}",
                preset.name
            );
        }
    }

    #[test]
    fn the_issue_names_are_there() {
        for name in [
            "paper-fig4-bloom",
            "paper-fig5-corona",
            "paper-fig5-both",
            "paper-fig6a",
            "paper-fig6b",
            "paper-fig6c",
            "paper-fig6d",
        ] {
            find(name).unwrap();
        }
        let e = find("paper-fig7").unwrap_err().to_string();
        assert!(
            e.contains("paper-fig7") && e.contains("paper-fig4-bloom"),
            "{e}"
        );
    }
}
