//! A group of controls for every effect type the library has, made from
//! its schema as the studio's panels are: each parameter with its unit,
//! range, default and line of help. A group switched on sets that effect
//! as its controls say: it replaces every effect of its type in the chain
//! the preset and the config file make, or joins the chain when it has
//! none.

use std::ffi::CStr;

use aureole::schema::{Default, Kind, Parameter};
use aureole::ConfigFile;

use crate::abi::names;
use crate::describe::{hint, number, Definer};
use crate::host::{Failure, Result};

/// The effect types with controls: all but a measured PSF, whose file
/// is the config's to name.
pub fn kinds() -> impl Iterator<Item = (&'static str, &'static [Parameter])> {
    aureole::config::effect_kinds().filter(|(kind, _)| *kind != aureole::optics::measured::KIND)
}

/// The control of `kind`'s parameter `p`.
pub fn control(kind: &str, p: &Parameter) -> String {
    format!("{kind}_{}", p.name)
}

/// What `p` starts at: its default, else the example preset's value.
fn default(kind: &str, p: &Parameter) -> Option<toml::Value> {
    match p.default {
        Default::Number(v) if p.kind == Kind::Whole => Some(toml::Value::Integer(v as i64)),
        Default::Number(v) => Some(toml::Value::Float(v)),
        Default::Length(text) | Default::Text(text) => Some(toml::Value::String(text.into())),
        Default::Flag(flag) => Some(toml::Value::Boolean(flag)),
        Default::Required => aureole::presets::example_table(kind)?.get(p.name).cloned(),
    }
}

/// The OpenFX type of `p`'s control: lengths ("10.4px", "60um") and
/// words are strings.
fn param_type(p: &Parameter) -> &'static CStr {
    match p.kind {
        Kind::Number | Kind::Angle => names::PARAM_TYPE_DOUBLE,
        Kind::Whole => names::PARAM_TYPE_INTEGER,
        Kind::Flag => names::PARAM_TYPE_BOOLEAN,
        Kind::Length | Kind::Text => names::PARAM_TYPE_STRING,
    }
}

/// Defines each effect type's group: a switch and its parameters.
pub fn define(d: &Definer<'_>) -> Result<()> {
    for (kind, parameters) in kinds() {
        let group = format!("{kind}_group");
        d(
            names::PARAM_TYPE_GROUP,
            &group,
            &format!("Effect: {kind}"),
            format!("the {kind} effect as these controls set it"),
            None,
        )?;
        let switch = d(
            names::PARAM_TYPE_BOOLEAN,
            kind,
            &format!("Set {kind} here"),
            format!(
                "on: this {kind} replaces every {kind} of the preset and the config file, \
                 or joins the chain when they have none"
            ),
            Some(&group),
        )?;
        switch.set_int(names::PARAM_DEFAULT, 0, 0)?;
        for p in parameters {
            let label = format!("{} {}", p.name, p.unit).trim().to_string();
            let props = d(
                param_type(p),
                &control(kind, p),
                &label,
                hint(p),
                Some(&group),
            )?;
            let low = p.low.map_or(-1e12, |(v, _)| v);
            let high = p.high.map_or(1e12, |(v, _)| v);
            match (p.kind, default(kind, p)) {
                (Kind::Whole, value) => {
                    let v = value.and_then(|v| v.as_integer()).unwrap_or(0);
                    props.set_int(names::PARAM_DEFAULT, 0, v as i32)?;
                    props.set_int(names::PARAM_MIN, 0, low.max(-1e9) as i32)?;
                    props.set_int(names::PARAM_MAX, 0, high.min(1e9) as i32)?;
                }
                (Kind::Number | Kind::Angle, value) => {
                    let v = value
                        .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
                        .unwrap_or(0.0);
                    let slider = (low.max(v.min(0.0)), high.min(4.0 * v.abs().max(1.0)));
                    number(&props, v, (low, high), slider)?;
                }
                (Kind::Flag, value) => {
                    let v = value.and_then(|v| v.as_bool()).unwrap_or(false);
                    props.set_int(names::PARAM_DEFAULT, 0, i32::from(v))?;
                }
                (Kind::Length | Kind::Text, value) => {
                    let v = value
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_default();
                    props.set_string(names::PARAM_DEFAULT, 0, &v)?;
                }
            }
        }
    }
    Ok(())
}

/// The effect types switched on, each with its controls' values.
pub type Overrides = Vec<(&'static str, toml::Table)>;

/// Reads the switched-on groups through `value`, which gives a control's
/// value as the TOML its parameter takes.
pub fn read(
    switched: impl Fn(&str) -> Result<bool>,
    value: impl Fn(&str, &Parameter) -> Result<toml::Value>,
) -> Result<Overrides> {
    let mut overrides = Vec::new();
    for (kind, parameters) in kinds() {
        if !switched(kind)? {
            continue;
        }
        let mut table = toml::Table::new();
        table.insert("type".into(), toml::Value::String(kind.into()));
        for p in parameters {
            let value = value(&control(kind, p), p)?;
            // As a config writes it: a value at its default is left out,
            // which some parameters need (a wavelength only for an
            // achromatic stop).
            if !at_default(p, &value) {
                table.insert(p.name.into(), value);
            }
        }
        overrides.push((kind, table));
    }
    Ok(overrides)
}

/// Whether `value` is `p`'s default, which a config leaves out.
fn at_default(p: &Parameter, value: &toml::Value) -> bool {
    match (p.default, value) {
        (Default::Number(d), toml::Value::Float(v)) => *v == d,
        (Default::Number(d), toml::Value::Integer(v)) => *v as f64 == d,
        (Default::Flag(d), toml::Value::Boolean(v)) => *v == d,
        (Default::Length(d) | Default::Text(d), toml::Value::String(v)) => v == d,
        _ => false,
    }
}

/// `file` with the switched-on effects set: each replaces the chain's
/// effects of its type, or joins the chain's end.
pub fn apply(file: ConfigFile, overrides: &Overrides) -> Result<ConfigFile> {
    if overrides.is_empty() {
        return Ok(file);
    }
    let said = |e: String| Failure::library(format!("the effect controls: {e}"));
    let mut table: toml::Table =
        toml::from_str(&file.to_toml()).map_err(|e| said(e.to_string()))?;
    let effects = table
        .entry("effect")
        .or_insert_with(|| toml::Value::Array(Vec::new()));
    let Some(effects) = effects.as_array_mut() else {
        return Err(said("the chain is not a list".into()));
    };
    for (kind, set) in overrides {
        let mut found = false;
        for effect in effects.iter_mut().filter_map(toml::Value::as_table_mut) {
            if effect.get("type").and_then(toml::Value::as_str) == Some(kind) {
                *effect = set.clone();
                found = true;
            }
        }
        if !found {
            effects.push(toml::Value::Table(set.clone()));
        }
    }
    ConfigFile::parse(&table.to_string(), "the effect controls").map_err(Failure::library)
}
