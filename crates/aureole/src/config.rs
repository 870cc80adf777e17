//! Configuration: TOML files and built-in presets, composed in order.
//!
//! A file may set `seed`, `threshold`, a `[camera]` table and any number of
//! `[[effect]]` tables (docs/configuration.md has the schema). Files compose: scalar
//! settings and camera fields set by a later file replace earlier ones, and
//! effects are appended to the optical chain.

use std::path::Path;

use serde::de::Error as _;
use serde::Deserialize;

use crate::camera::CameraGeometry;
use crate::check;
use crate::control::{Cancel, Control};
use crate::convolve::Composing;
use crate::error::{Error, Result};
use crate::kernel::{self, Extent, Kernel};
use crate::lens::effect::{self as ghosts, Ghosts};
use crate::optics::Effect;

/// What one config file or preset says; unset keys stay `None` so that
/// files compose.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConfigFile {
    /// A one-line description (presets have one).
    pub description: Option<String>,
    /// Seed of the ray randomness.
    pub seed: Option<u64>,
    /// Luminance threshold in cd/m²: pixels at or below it are not spread.
    pub threshold: Option<f64>,
    /// Camera fields, if the file has a `[camera]` table.
    pub camera: Option<CameraGeometry>,
    /// The `[[effect]]` tables, in order.
    pub effects: Vec<Effect>,
    /// The lens ghosts, if an `[[effect]]` table of `type = "ghosts"`
    /// asks for them: a stage of their own, before the kernel's chain.
    pub ghosts: Option<Ghosts>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    description: Option<String>,
    seed: Option<u64>,
    threshold: Option<toml::Spanned<f64>>,
    camera: Option<toml::Spanned<CameraGeometry>>,
    #[serde(default)]
    effect: Vec<toml::Spanned<toml::Table>>,
}

impl ConfigFile {
    /// Parses and checks a config text; `source_name` (a file name, or
    /// `preset NAME`) starts every error message, with the line and column.
    /// A ghosts' lens file is read from where its path leads.
    pub fn parse(text: &str, source_name: &str) -> Result<ConfigFile> {
        ConfigFile::parse_in(text, source_name, Some(Path::new("")))
    }

    /// [`ConfigFile::parse`], a ghosts' lens file read from `folder` (the
    /// config file's) when its path is relative; with no folder, a lens
    /// file is refused (a server reads no files but those it is given).
    pub fn parse_in(text: &str, source_name: &str, folder: Option<&Path>) -> Result<ConfigFile> {
        let place = |span: std::ops::Range<usize>, message: String, incomplete: Option<String>| {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            Error::Config {
                source_name: source_name.to_string(),
                line,
                column,
                message: printable(&message),
                incomplete_effect: incomplete,
            }
        };
        let located = |span, message| place(span, message, None);
        let raw: RawFile = toml::from_str(text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            let message = match key_at(text, span.start) {
                Some(key) if is_type_error(e.message()) => {
                    format!("`{key}`: {}", plain_types(e.message()))
                }
                _ => with_suggestion(e.message()),
            };
            located(span, message)
        })?;

        if let Some(threshold) = &raw.threshold {
            check::range(
                "config",
                "threshold",
                *threshold.get_ref(),
                *threshold.get_ref() >= 0.0,
                "a luminance in cd/m² of at least 0",
            )
            .map_err(|e| located(threshold.span(), e.to_string()))?;
        }
        if let Some(camera) = &raw.camera {
            camera
                .get_ref()
                .validate()
                .map_err(|e| located(camera.span(), e.to_string()))?;
        }
        let mut effects = Vec::with_capacity(raw.effect.len());
        let mut ghosts: Option<Ghosts> = None;
        for (index, table) in raw.effect.into_iter().enumerate() {
            let span = table.span();
            let context = |kind: &str| format!("effect {} ({kind})", index + 1);
            let kind = table
                .get_ref()
                .get("type")
                .and_then(toml::Value::as_str)
                .map_or_else(
                    || "without a type".to_string(),
                    // Whatever the file holds there is echoed: keep it short.
                    |kind| kind.chars().take(40).collect(),
                );
            let table = table.into_inner();
            let keys = table.clone();
            let refused = |e: toml::de::Error| {
                let message = match key_holding(&keys, e.message()) {
                    Some(key) if is_type_error(e.message()) => {
                        format!("`{key}`: {}", plain_types(e.message()))
                    }
                    _ => match length_key(&keys, e.message()) {
                        Some(key) => format!("`{key}`: {}", e.message()),
                        None => with_suggestion(e.message()),
                    },
                };
                let incomplete = message.starts_with("missing field").then(|| kind.clone());
                place(
                    key_span(text, &span, &message),
                    format!("{}: {message}", context(&kind)),
                    incomplete,
                )
            };
            if kind == ghosts::KIND {
                let mut table = table;
                table.remove("type");
                let read = ghosts::Table::deserialize(toml::Value::Table(table))
                    .map_err(refused)?
                    .resolve(folder)
                    .map_err(|e| {
                        let key = match &e {
                            Error::Parameter { name, .. } => format!("`{name}`"),
                            _ => "`lens`".to_string(),
                        };
                        located(
                            key_span(text, &span, &key),
                            format!("{}: {e}", context(ghosts::KIND)),
                        )
                    })?;
                if ghosts.replace(read).is_some() {
                    return Err(located(
                        span,
                        format!(
                            "{}: a camera has one lens: write one [[effect]] of type = \"ghosts\"",
                            context(ghosts::KIND)
                        ),
                    ));
                }
                continue;
            }
            // The ghosts are read apart (they are no kernel): a misspelt
            // type is refused here, listing every type a table may name.
            let named = keys.get("type").and_then(toml::Value::as_str);
            if named.is_some_and(|t| !crate::optics::EFFECT_TYPES.contains(&t)) {
                let listed: Vec<String> = effect_kinds().map(|(t, _)| format!("`{t}`")).collect();
                return Err(refused(toml::de::Error::custom(format!(
                    "unknown variant `{kind}`, expected one of {}",
                    listed.join(", ")
                ))));
            }
            let effect = Effect::from_table(table).map_err(refused)?;
            // A wavelength the spectral kernel would ignore is a mistake:
            // the user meant an achromatic one.
            let spectral = keys.get("spectral").and_then(toml::Value::as_bool) != Some(false);
            if keys.contains_key("wavelength_nm") && spectral {
                return Err(located(
                    key_span(text, &span, "`wavelength_nm`"),
                    format!(
                        "{}: `wavelength_nm` is the wavelength of an achromatic kernel; a spectral one (the default) covers 380–780 nm: add `spectral = false` to use it, or remove it",
                        context(effect.kind())
                    ),
                ));
            }
            effect.validate().map_err(|e| {
                let at = match &e {
                    Error::Parameter { name, .. } => key_span(text, &span, &format!("`{name}`")),
                    _ => span.clone(),
                };
                located(at, format!("{}: {e}", context(effect.kind())))
            })?;
            effects.push(effect);
        }
        Ok(ConfigFile {
            description: raw.description,
            seed: raw.seed,
            threshold: raw.threshold.map(toml::Spanned::into_inner),
            camera: raw.camera.map(toml::Spanned::into_inner),
            effects,
            ghosts,
        })
    }

    /// The `type` of each of its `[[effect]]` tables: the ghosts first
    /// (their stage comes first), then the chain's.
    pub fn kinds(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.ghosts
            .iter()
            .map(|_| ghosts::KIND)
            .chain(self.effects.iter().map(Effect::kind))
    }

    /// Reads and parses a config file.
    pub fn load(path: &Path) -> Result<ConfigFile> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        ConfigFile::parse_in(&text, &path.display().to_string(), path.parent())
    }

    /// `later` on top of this file, as the command line composes files:
    /// settings and camera fields `later` sets replace ours, its effects
    /// follow ours; a description is the composition's no longer.
    pub fn then(mut self, later: ConfigFile) -> ConfigFile {
        self.description = None;
        self.seed = later.seed.or(self.seed);
        self.threshold = later.threshold.or(self.threshold);
        self.camera = match (self.camera, later.camera) {
            (Some(mut ours), Some(theirs)) => {
                ours.merge(&theirs);
                Some(ours)
            }
            (ours, theirs) => theirs.or(ours),
        };
        self.effects.extend(later.effects);
        self.ghosts = later.ghosts.or(self.ghosts);
        self
    }

    /// The file as TOML text that [`ConfigFile::parse`] reads back as the
    /// same settings: what is set, and each effect's parameters that differ
    /// from their defaults.
    pub fn to_toml(&self) -> String {
        let mut table = toml::Table::new();
        let mut set = |key: &str, value: Option<toml::Value>| {
            if let Some(value) = value {
                table.insert(key.to_string(), value);
            }
        };
        set(
            "description",
            self.description.clone().map(toml::Value::String),
        );
        // A seed above i64::MAX cannot be written in TOML, nor read from it.
        set(
            "seed",
            self.seed
                .and_then(|seed| i64::try_from(seed).ok())
                .map(toml::Value::Integer),
        );
        set("threshold", self.threshold.map(toml::Value::Float));
        set(
            "camera",
            self.camera
                .and_then(|camera| toml::Table::try_from(camera).ok())
                .map(toml::Value::Table),
        );
        if !self.effects.is_empty() || self.ghosts.is_some() {
            let effects = self
                .ghosts
                .iter()
                .map(Ghosts::to_table)
                .chain(self.effects.iter().map(Effect::to_table));
            set(
                "effect",
                Some(toml::Value::Array(
                    effects.map(toml::Value::Table).collect(),
                )),
            );
        }
        table.to_string()
    }
}

/// Every `type` an `[[effect]]` table may name, with its parameters: the
/// kernel's effects, then the lens ghosts (a stage of their own).
pub fn effect_kinds() -> impl Iterator<Item = (&'static str, &'static [crate::schema::Parameter])> {
    crate::optics::EFFECT_PARAMETERS
        .iter()
        .copied()
        .chain([(ghosts::KIND, ghosts::PARAMETERS)])
}

/// `text` with control characters (a newline in a quoted value, say)
/// escaped, so that a message stays one line.
fn printable(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// A serde message on one line, with "did you mean" when it refuses a name
/// (unknown field `radus`, expected one of `radius`, …) close to an allowed one.
fn with_suggestion(message: &str) -> String {
    let mut line = message.trim().replace('\n', " ");
    let quoted: Vec<&str> = line.split('`').skip(1).step_by(2).collect();
    let refused = line.starts_with("unknown field") || line.starts_with("unknown variant");
    if let (true, Some((found, allowed))) = (refused, quoted.split_first()) {
        if let Some(close) = crate::error::closest(found, allowed.iter().copied()) {
            let close = close.to_string();
            line.push_str(&format!("; did you mean `{close}`?"));
        }
    }
    line
}

/// Whether serde refused a value for its type or range, a message that
/// names no key.
fn is_type_error(message: &str) -> bool {
    message.starts_with("invalid type") || message.starts_with("invalid value")
}

/// Serde's type names in words: `expected u64` is "a whole number of at
/// least 0".
fn plain_types(message: &str) -> String {
    let words = [
        ("expected u8", "expected a whole number of at least 0"),
        ("expected u16", "expected a whole number of at least 0"),
        ("expected u64", "expected a whole number of at least 0"),
        ("expected u32", "expected a whole number of at least 0"),
        ("expected usize", "expected a whole number of at least 0"),
        ("expected i64", "expected a whole number"),
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
    ];
    let mut line = message.trim().replace('\n', " ");
    for (serde, plain) in words {
        line = line.replace(serde, plain);
    }
    line
}

/// The key written on the line of `text` at byte `offset` (`seed` in
/// `seed = -1`).
fn key_at(text: &str, offset: usize) -> Option<String> {
    let start = text.get(..offset)?.rfind('\n').map_or(0, |i| i + 1);
    let line = text[start..].lines().next()?;
    let (key, _) = line.split_once('=')?;
    let key = key.trim().trim_matches('"').trim_matches('\'');
    (!key.is_empty() && !key.starts_with('[')).then(|| key.to_string())
}

/// The key of `table` whose value serde's `message` quotes (`invalid type:
/// string "two", expected f64`), when exactly one has it.
fn key_holding(table: &toml::Table, message: &str) -> Option<String> {
    let shown = |value: &toml::Value| match value {
        toml::Value::String(s) => Some(format!("string {s:?}")),
        toml::Value::Integer(i) => Some(format!("integer `{i}`")),
        // serde quotes 7.0 as `7.0`, which `{}` would print as 7.
        toml::Value::Float(f) => Some(format!("floating point `{f:?}`")),
        toml::Value::Boolean(b) => Some(format!("boolean `{b}`")),
        toml::Value::Array(_) => Some("sequence".to_string()),
        toml::Value::Table(_) => Some("map".to_string()),
        toml::Value::Datetime(_) => None,
    };
    let mut found = table
        .iter()
        .filter(|(_, v)| shown(v).is_some_and(|s| message.contains(&s)))
        .map(|(k, _)| k.clone());
    match (found.next(), found.next()) {
        (Some(key), None) => Some(key),
        _ => None,
    }
}

/// The key of `table` whose length `message` refuses (its words quote the
/// length, not the key that holds it), when one key holds it.
fn length_key(table: &toml::Table, message: &str) -> Option<String> {
    let mut found = table
        .iter()
        .filter(|(_, v)| {
            v.as_str()
                .is_some_and(|s| message.starts_with(&format!("length {s:?} is not valid")))
        })
        .map(|(k, _)| k.clone());
    match (found.next(), found.next()) {
        (Some(key), None) => Some(key),
        _ => None,
    }
}

/// Where, in the `[[effect]]` table whose header is at `header`, the key that
/// `message` names (as serde quotes it: unknown field `radus`) is written;
/// the header itself when the message names no key found there.
fn key_span(text: &str, header: &std::ops::Range<usize>, message: &str) -> std::ops::Range<usize> {
    let Some(key) = message.split('`').nth(1).filter(|k| !k.is_empty()) else {
        return header.clone();
    };
    let mut offset = header.end;
    for line in text.get(header.end..).unwrap_or("").split_inclusive('\n') {
        let trimmed = line.trim_start();
        if trimmed.starts_with('[') {
            break;
        }
        if let Some(rest) = trimmed.strip_prefix(key) {
            if rest.trim_start().starts_with('=') {
                let start = offset + (line.len() - trimmed.len());
                return start..start + key.len();
            }
        }
        offset += line.len();
    }
    header.clone()
}

/// The composed configuration: everything needed to build a kernel and apply
/// it.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Seed of the ray randomness (default 1).
    pub seed: u64,
    /// Luminance threshold in cd/m² (default 0: every pixel is spread).
    pub threshold: f64,
    /// The camera (every field optional).
    pub camera: CameraGeometry,
    /// The optical chain, in order.
    pub effects: Vec<Effect>,
    /// The lens ghosts, traced before the chain spreads the scene.
    pub ghosts: Option<Ghosts>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            seed: 1,
            threshold: 0.0,
            camera: CameraGeometry::default(),
            effects: Vec::new(),
            ghosts: None,
        }
    }
}

impl Config {
    /// The first aperture of the chain: the stop whose optics its
    /// diffraction and its lens ghosts share.
    pub fn first_aperture(&self) -> Option<&crate::Aperture> {
        self.effects.iter().find_map(|e| match e {
            Effect::Aperture(a) => Some(a),
            _ => None,
        })
    }

    /// The same camera for the image resampled by `factor` (a preview of
    /// width W·factor): lengths in pixels scale with it, while lengths on
    /// the sensor and diffraction follow from the new pixel pitch, so the
    /// kernel draws what the full image's kernel draws, smaller.
    pub fn with_pixels_scaled(&self, factor: f64) -> Config {
        let mut scaled = self.clone();
        for effect in &mut scaled.effects {
            effect.scale_pixels(factor);
        }
        scaled
    }

    /// The files composed in order on the defaults ([`Config::merge`]).
    pub fn compose(files: impl IntoIterator<Item = ConfigFile>) -> Config {
        let mut config = Config::default();
        for file in files {
            config.merge(file);
        }
        config
    }

    /// Adds a file on top: its settings replace ours, its effects follow ours.
    pub fn merge(&mut self, file: ConfigFile) {
        self.seed = file.seed.unwrap_or(self.seed);
        self.threshold = file.threshold.unwrap_or(self.threshold);
        if let Some(camera) = &file.camera {
            self.camera.merge(camera);
        }
        self.effects.extend(file.effects);
        if file.ghosts.is_some() {
            self.ghosts = file.ghosts;
        }
    }

    /// The kernel of the whole optical chain at `extent`.
    pub fn kernel(&self, extent: &Extent) -> Result<Kernel> {
        self.kernel_with(extent, &mut Control::quiet(&Cancel::new()))
    }

    /// [`Config::kernel`], reporting to `control` and stopping when it is
    /// cancelled.
    pub fn kernel_with(&self, extent: &Extent, control: &mut Control) -> Result<Kernel> {
        self.kernel_on(extent, &mut Composing::cpu(), control)
    }

    /// [`Config::kernel_with`], its effects convolving one another where
    /// `composing` says (on a GPU, bits apart from the CPU's).
    pub fn kernel_on(
        &self,
        extent: &Extent,
        composing: &mut Composing,
        control: &mut Control,
    ) -> Result<Kernel> {
        kernel::build(
            &self.camera,
            &self.effects,
            self.seed,
            extent,
            composing,
            control,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::Length;

    const SCHEMA: &str = r#"
seed = 1
threshold = 0.0

[camera]
sensor_width_mm = 36.0
focal_length_mm = 50.0
f_number = 8.0

[[effect]]
type = "bloom"
epsilon = 0.005
beta = 2.0
radius = "10.4px"

[[effect]]
type = "corona"
epsilon = 0.005
rays = 14
length = "15.6px"
fadeout = 1.0
width = "3px"
spread = 1.0
length_jitter = 0.25
rotation_deg = 0.0

[[effect]]
type = "vos"
epsilon = 0.05
exponent = 2.0
"#;

    #[test]
    fn parses_the_public_schema() {
        let file = ConfigFile::parse(SCHEMA, "schema.toml").unwrap();
        assert_eq!(file.seed, Some(1));
        assert_eq!(file.camera.unwrap().focal_length_mm, Some(50.0));
        let kinds: Vec<_> = file.effects.iter().map(Effect::kind).collect();
        assert_eq!(kinds, ["bloom", "corona", "vos"]);
        match &file.effects[0] {
            Effect::Bloom(b) => assert_eq!(b.radius, Length::px(10.4)),
            other => panic!("{other:?}"),
        }
    }

    fn error(text: &str) -> String {
        ConfigFile::parse(text, "my.toml").unwrap_err().to_string()
    }

    #[test]
    fn unknown_keys_list_what_is_allowed() {
        let e = error("[[effect]]\ntype = \"bloom\"\nepsilon = 0.1\nbeta = 2.0\nradus = \"3px\"\n");
        assert!(e.starts_with("my.toml:5:1: "), "{e}");
        assert!(e.contains("radus") && e.contains("radius"), "{e}");
        let e = error("sead = 3\n");
        assert!(
            e.contains("sead") && e.contains("seed") && e.contains("effect"),
            "{e}"
        );
    }

    #[test]
    fn a_length_refused_names_its_key_and_line() {
        let e = error(
            "[[effect]]\ntype = \"bloom\"\nepsilon = 0.1\nbeta = 2.0\nradius = \"ten pixels\"\n",
        );
        assert!(e.starts_with("my.toml:5:1: "), "{e}");
        assert!(
            e.contains("`radius`: length \"ten pixels\" is not valid"),
            "{e}"
        );
    }

    #[test]
    fn unknown_effect_types_list_the_types() {
        let e = error("[[effect]]\ntype = \"blom\"\nepsilon = 0.1\n");
        assert!(e.starts_with("my.toml:"), "{e}");
        for (kind, _) in effect_kinds() {
            assert!(e.contains(kind), "{e}");
        }
        assert!(e.contains("ghosts"), "{e}");
        // A type that is no string is refused as such.
        let e = error("[[effect]]\ntype = 3\n");
        assert!(e.contains("is not a string"), "{e}");
    }

    #[test]
    fn out_of_range_values_name_file_effect_and_parameter() {
        let e =
            error("[[effect]]\ntype = \"bloom\"\nepsilon = 0.1\nbeta = 0.5\nradius = \"3px\"\n");
        // The position is the offending key's.
        assert!(e.starts_with("my.toml:4:1:"), "{e}");
        assert!(
            e.contains("effect 1 (bloom)") && e.contains("beta = 0.5"),
            "{e}"
        );
        let e = error("threshold = -1.0\n");
        assert!(
            e.contains("threshold = -1") && e.contains("at least 0"),
            "{e}"
        );
        let e = error("[camera]\nsensor_width_mm = 0.0\n");
        assert!(e.contains("sensor_width_mm = 0"), "{e}");
    }

    #[test]
    fn lengths_need_units() {
        let e = error("[[effect]]\ntype = \"bloom\"\nepsilon = 0.1\nbeta = 2.0\nradius = 10.4\n");
        assert!(e.contains("no unit") && e.contains("\"10.4px\""), "{e}");
    }

    #[test]
    fn a_float_where_a_whole_number_belongs_names_the_key_and_its_line() {
        let text = "seed = 3\n\n[[effect]]\ntype = \"aperture\"\nblades = 7.0\n";
        let e = ConfigFile::parse(text, "lens.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("lens.toml:5:"), "{e}");
        assert!(
            e.contains("`blades`") && e.contains("7.0") && e.contains("a whole number"),
            "{e}"
        );
    }

    #[test]
    fn later_files_override_settings_and_append_effects() {
        let mut config = Config::default();
        config.merge(ConfigFile::parse(SCHEMA, "a").unwrap());
        config.merge(
            ConfigFile::parse(
                "seed = 9\n[camera]\nf_number = 2.8\n[[effect]]\ntype = \"vos\"\nepsilon = 0.1\n",
                "b",
            )
            .unwrap(),
        );
        assert_eq!(config.seed, 9);
        assert_eq!(config.camera.f_number, Some(2.8));
        assert_eq!(config.camera.focal_length_mm, Some(50.0));
        assert_eq!(config.effects.len(), 4);
    }
}
