//! The camera as the page's panels see it: the library's schema of every
//! parameter, and a config's TOML read into a table and written back.

use aureole::schema::{Default, Kind, Parameter, CAMERA};
use serde_json::{json, Value};

use crate::error::StudioError;

fn parameter(p: &Parameter) -> Value {
    let bound =
        |b: Option<(f64, bool)>| b.map(|(v, closed)| json!({ "value": v, "closed": closed }));
    json!({
        "name": p.name,
        "kind": match p.kind {
            Kind::Number => "number",
            Kind::Whole => "whole",
            Kind::Angle => "angle",
            Kind::Length => "length",
            Kind::Flag => "flag",
            Kind::Text => "text",
        },
        "low": bound(p.low),
        "high": bound(p.high),
        "default": match p.default {
            Default::Required => Value::Null,
            Default::Number(v) => json!(v),
            Default::Length(text) => json!(text),
            Default::Flag(flag) => json!(flag),
            Default::Text(text) => json!(text),
        },
        "unit": p.unit,
        "allowed": p.allowed,
        "about": p.about,
    })
}

/// `GET /api/schema`: the camera's and every effect's parameters, and for
/// each effect an example table to add it from (the first preset that has
/// one).
pub fn schema() -> Value {
    use aureole::lens::{effect, shipped};
    let lenses: Vec<&str> = shipped::LENSES.iter().map(|l| l.name).collect();
    let effects: Vec<Value> = aureole::config::effect_kinds()
        // A measured PSF names a file of its own, which the studio does
        // not read (render::parse_config refuses it): no panel offers it.
        .filter(|(kind, _)| *kind != aureole::optics::measured::KIND)
        .map(|(kind, parameters)| {
            // The aperture's star-filter families are tables of their own.
            let tables = if kind == "aperture" {
                let filter = aureole::optics::aperture::FILTER_PARAMETERS;
                json!({ "filter": filter.iter().map(parameter).collect::<Vec<_>>() })
            } else {
                json!({})
            };
            let parameters: Vec<Value> = parameters
                .iter()
                .map(|p| {
                    let mut shown = parameter(p);
                    // The ghosts' lens is a shipped one: the studio reads
                    // no lens files.
                    if kind == effect::KIND && p.name == "lens" {
                        shown["choices"] = json!(lenses);
                    }
                    shown
                })
                .collect();
            json!({
                "type": kind,
                "parameters": parameters,
                "tables": tables,
                "example": example(kind),
            })
        })
        .collect();
    json!({
        "camera": CAMERA.iter().map(parameter).collect::<Vec<_>>(),
        "effects": effects,
    })
}

fn example(kind: &str) -> Value {
    aureole::presets::example_table(kind)
        .and_then(|t| serde_json::to_value(t).ok())
        .unwrap_or(Value::Null)
}

/// `POST /api/config/read`: a config's TOML as a JSON table, once the
/// library accepts it (so the panels never show a camera that would be
/// refused).
pub fn read(text: &str) -> Result<Value, StudioError> {
    crate::render::parse_config(text)?;
    let table: toml::Table = toml::from_str(text)
        .map_err(|e| StudioError::BadRequest(format!("config: {}", e.message())))?;
    serde_json::to_value(table).map_err(|e| StudioError::Internal(e.to_string()))
}

/// `POST /api/config/write`: a JSON table as a config's TOML.
pub fn write(value: Value) -> Result<String, StudioError> {
    let table: toml::Table = serde_json::from_value(value)
        .map_err(|e| StudioError::BadRequest(format!("the camera: {e}")))?;
    toml::to_string(&table).map_err(|e| StudioError::BadRequest(format!("the camera: {e}")))
}
