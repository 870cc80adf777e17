//! A lens file's TOML, read and checked; and written back.

use std::fmt::Write as _;
use std::ops::Range;

use serde::Deserialize;
use toml::Spanned;

use super::{Coating, Layer, Lens, Medium, Patent, Surface};
use crate::error::{Error, Result};

/// What `coating` may be, in words.
const COATINGS: &str = "write \"none\", \"mgf2\" (a quarter wave of MgF₂ at 550 nm), { index = 1.38, design_nm = 550 } (one quarter-wave layer) or { layers = [{ index = 2.1, thickness_nm = 65 }, …] } (from the front medium inwards)";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLens {
    name: String,
    /// Scales the prescription to this focal length, mm.
    focal_length_mm: Option<Spanned<f64>>,
    /// The default of every air–glass surface.
    coating: Option<Spanned<toml::Value>>,
    patent: Option<RawPatent>,
    #[serde(default)]
    surface: Vec<Spanned<RawSurface>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPatent {
    number: String,
    example: String,
    focal_length: Option<f64>,
    back_focus: Option<f64>,
    f_number: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSurface {
    radius: Option<Spanned<toml::Value>>,
    radius_y: Option<Spanned<toml::Value>>,
    #[serde(default)]
    thickness: f64,
    n_d: Option<f64>,
    v_d: Option<f64>,
    semi_aperture: f64,
    coating: Option<Spanned<toml::Value>>,
    #[serde(default)]
    stop: bool,
}

/// The lens in `text`, checked.
pub(super) fn lens(text: &str, source_name: &str) -> Result<Lens> {
    let place = |span: Range<usize>, message: String| {
        let before = &text[..span.start.min(text.len())];
        Error::Config {
            source_name: source_name.to_string(),
            line: before.matches('\n').count() + 1,
            column: before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1,
            message,
            incomplete_effect: None,
        }
    };
    let raw: RawLens = toml::from_str(text)
        .map_err(|e| place(e.span().unwrap_or(0..0), e.message().to_string()))?;
    let default = match &raw.coating {
        Some(value) => coating(value.get_ref()).map_err(|m| place(value.span(), m))?,
        None => Coating::magnesium_fluoride(),
    };
    let mut surfaces = Vec::with_capacity(raw.surface.len());
    let mut spans = Vec::with_capacity(raw.surface.len());
    let mut before = Medium::Air;
    for (i, spanned) in raw.surface.iter().enumerate() {
        let span = spanned.span();
        let s = spanned.get_ref();
        let at = |m: String| place(span.clone(), format!("surface {}: {m}", i + 1));
        let read = |key: &str, value: &Spanned<toml::Value>| {
            radius(key, value.get_ref())
                .map_err(|m| place(value.span(), format!("surface {}: {m}", i + 1)))
        };
        let radius = s
            .radius
            .as_ref()
            .map(|v| read("radius", v))
            .transpose()?
            .flatten();
        let radius_y = s
            .radius_y
            .as_ref()
            .map(|v| read("radius_y", v))
            .transpose()?;
        let medium = match (s.n_d, s.v_d) {
            (None, None) if s.stop => before,
            (None, None) => Medium::Air,
            (Some(n_d), v_d) => Medium::Glass { n_d, v_d },
            (None, Some(_)) => return Err(at("v_d without n_d: a glass needs its n_d".into())),
        };
        let coating = match &s.coating {
            Some(value) => coating(value.get_ref())
                .map_err(|m| place(value.span(), format!("surface {}: {m}", i + 1)))?,
            None => Coating::unless_given(before, medium, &default),
        };
        surfaces.push(Surface {
            radius,
            radius_y,
            thickness: s.thickness,
            medium,
            semi_aperture: s.semi_aperture,
            coating,
            stop: s.stop,
        });
        spans.push(span);
        before = medium;
    }
    let patent = raw.patent.map(|p| Patent {
        number: p.number,
        example: p.example,
        focal_length: p.focal_length,
        back_focus: p.back_focus,
        f_number: p.f_number,
    });
    let mut lens = Lens {
        name: raw.name,
        patent,
        mm_per_unit: 1.0,
        surfaces,
    };
    if let Err((surface, message)) = problems(&lens) {
        let span = surface.and_then(|i| spans.get(i).cloned()).unwrap_or(0..0);
        return Err(place(span, message));
    }
    if let Some(focal) = raw.focal_length_mm {
        let f = *focal.get_ref();
        if !(f.is_finite() && f > 0.0) {
            return Err(place(
                focal.span(),
                format!("focal_length_mm = {f} is not allowed: a length in mm above 0"),
            ));
        }
        let paraxial = lens
            .paraxial()
            .map_err(|e| place(focal.span(), e.to_string()))?;
        lens.mm_per_unit = f / paraxial.focal_length;
    }
    Ok(lens)
}

/// A radius (`key`): a number other than 0, or "flat".
fn radius(key: &str, value: &toml::Value) -> std::result::Result<Option<f64>, String> {
    let refuse = || {
        format!("{key} = {value} is not allowed: a radius of curvature other than 0 (positive: its centre lies behind the surface), or \"flat\" for a plane")
    };
    match value {
        toml::Value::String(s) if s == "flat" => Ok(None),
        toml::Value::Float(r) if r.is_finite() && *r != 0.0 => Ok(Some(*r)),
        toml::Value::Integer(r) if *r != 0 => Ok(Some(*r as f64)),
        _ => Err(refuse()),
    }
}

/// A coating as [`COATINGS`] says.
fn coating(value: &toml::Value) -> std::result::Result<Coating, String> {
    let number = |table: &toml::Table, key: &str| match table.get(key) {
        Some(toml::Value::Float(x)) => Some(*x),
        Some(toml::Value::Integer(x)) => Some(*x as f64),
        _ => None,
    };
    let refuse = || format!("coating = {value} is not known: {COATINGS}");
    let layer = |index: Option<f64>, thickness_nm: Option<f64>| match (index, thickness_nm) {
        (Some(index), Some(thickness_nm)) => Ok(Layer {
            index,
            thickness_nm,
        }),
        _ => Err(refuse()),
    };
    match value {
        toml::Value::String(s) if s == "none" => Ok(Coating::None),
        toml::Value::String(s) if s == "mgf2" => Ok(Coating::magnesium_fluoride()),
        toml::Value::Table(table) => {
            let keys: Vec<&str> = table.keys().map(String::as_str).collect();
            match keys.as_slice() {
                ["index"] | ["design_nm", "index"] => {
                    let design = number(table, "design_nm").unwrap_or(super::DESIGN_NM);
                    let index = number(table, "index").ok_or_else(refuse)?;
                    let quarter = layer(Some(index), Some(design / (4.0 * index)))?;
                    Ok(Coating::Layers(vec![quarter]))
                }
                ["layers"] => {
                    let Some(toml::Value::Array(layers)) = table.get("layers") else {
                        return Err(refuse());
                    };
                    layers
                        .iter()
                        .map(|l| match l {
                            toml::Value::Table(t) if t.len() == 2 => {
                                layer(number(t, "index"), number(t, "thickness_nm"))
                            }
                            _ => Err(refuse()),
                        })
                        .collect::<std::result::Result<Vec<_>, _>>()
                        .map(Coating::Layers)
                }
                _ => Err(refuse()),
            }
        }
        _ => Err(refuse()),
    }
}

/// What makes `lens` no lens, one line; the surface it is about, if one.
pub(super) fn check(lens: &Lens) -> std::result::Result<(), String> {
    problems(lens).map_err(|(_, message)| message)
}

fn problems(lens: &Lens) -> std::result::Result<(), (Option<usize>, String)> {
    let whole = |m: &str| Err((None, m.to_string()));
    if lens.surfaces.len() < 2 {
        return whole(
            "a lens needs at least two surfaces ([[surface]] tables), the stop among them",
        );
    }
    let stops = lens.surfaces.iter().filter(|s| s.stop).count();
    if stops != 1 {
        return Err((
            None,
            format!("a lens needs exactly one surface with stop = true, not {stops}"),
        ));
    }
    if !lens.surfaces.iter().any(|s| s.medium.is_glass()) {
        return whole(
            "a lens needs glass: give some surface the n_d (and v_d) of the glass after it",
        );
    }
    for (i, s) in lens.surfaces.iter().enumerate() {
        let at = |m: String| Err((Some(i), format!("surface {}: {m}", i + 1)));
        if !(s.thickness.is_finite() && s.thickness >= 0.0) {
            return at(format!(
                "thickness = {} is not allowed: the distance to the next surface, 0 or more",
                s.thickness
            ));
        }
        if !(s.semi_aperture.is_finite() && s.semi_aperture > 0.0) {
            return at(format!(
                "semi_aperture = {} is not allowed: the clear semi-aperture, above 0",
                s.semi_aperture
            ));
        }
        for (key, r) in [("radius", s.radius), ("radius_y", s.radius_y.flatten())] {
            if let Some(r) = r.filter(|r| s.semi_aperture > r.abs()) {
                return at(format!(
                    "semi_aperture = {} exceeds |{key}| = {}: the surface's curve reaches no farther from its axis",
                    s.semi_aperture,
                    r.abs()
                ));
            }
        }
        if let Medium::Glass { n_d, v_d } = s.medium {
            if !(1.0..=3.0).contains(&n_d) {
                return at(format!("n_d = {n_d} is not allowed: an index from 1 to 3"));
            }
            if let Some(v) = v_d.filter(|v| !(5.0..=150.0).contains(v)) {
                return at(format!(
                    "v_d = {v} is not allowed: an Abbe number from 5 to 150"
                ));
            }
        }
        if s.stop
            && (s.radius.is_some() || s.radius_y.is_some() || s.medium != lens.medium_before(i))
        {
            return at(
                "the stop is a plane in the medium before it: give it no radius, radius_y, n_d or v_d".into(),
            );
        }
        if let Coating::Layers(layers) = &s.coating {
            for layer in layers {
                let allowed = (1.0..=3.0).contains(&layer.index)
                    && layer.thickness_nm > 0.0
                    && layer.thickness_nm <= 10_000.0;
                if !allowed {
                    return at(format!(
                        "a coating layer of index {} and {} nm is not allowed: an index from 1 to 3, a thickness above 0 and up to 10000 nm",
                        layer.index, layer.thickness_nm
                    ));
                }
            }
        }
    }
    if lens.surfaces.last().map(|s| s.medium) != Some(Medium::Air) {
        return Err((
            Some(lens.surfaces.len() - 1),
            "the last surface must leave the light in air: give it no n_d".into(),
        ));
    }
    Ok(())
}

/// `lens` in the schema [`lens`] reads.
pub(super) fn to_toml(lens: &Lens) -> String {
    let mut out = String::new();
    let quoted = |s: &str| toml::Value::String(s.to_string()).to_string();
    let _ = writeln!(out, "name = {}", quoted(&lens.name));
    if lens.mm_per_unit != 1.0 {
        if let Ok(p) = lens.paraxial() {
            let _ = writeln!(
                out,
                "focal_length_mm = {}",
                p.focal_length * lens.mm_per_unit
            );
        }
    }
    if let Some(p) = &lens.patent {
        let _ = writeln!(out, "\n[patent]\nnumber = {}", quoted(&p.number));
        let _ = writeln!(out, "example = {}", quoted(&p.example));
        for (key, value) in [
            ("focal_length", p.focal_length),
            ("back_focus", p.back_focus),
            ("f_number", p.f_number),
        ] {
            if let Some(v) = value {
                let _ = writeln!(out, "{key} = {v:?}");
            }
        }
    }
    for s in &lens.surfaces {
        out.push_str("\n[[surface]]\n");
        if s.stop {
            out.push_str("stop = true\n");
        } else {
            match s.radius {
                Some(r) => {
                    let _ = writeln!(out, "radius = {r:?}");
                }
                None => out.push_str("radius = \"flat\"\n"),
            }
            match s.radius_y {
                Some(Some(r)) => {
                    let _ = writeln!(out, "radius_y = {r:?}");
                }
                Some(None) => out.push_str("radius_y = \"flat\"\n"),
                None => {}
            }
        }
        let _ = writeln!(out, "thickness = {:?}", s.thickness);
        if let (Medium::Glass { n_d, v_d }, false) = (s.medium, s.stop) {
            let _ = writeln!(out, "n_d = {n_d:?}");
            if let Some(v) = v_d {
                let _ = writeln!(out, "v_d = {v:?}");
            }
        }
        let _ = writeln!(out, "semi_aperture = {:?}", s.semi_aperture);
        let coating = match &s.coating {
            Coating::None => "\"none\"".to_string(),
            c if *c == Coating::magnesium_fluoride() => "\"mgf2\"".to_string(),
            Coating::Layers(layers) => {
                let layers: Vec<String> = layers
                    .iter()
                    .map(|l| {
                        format!(
                            "{{ index = {:?}, thickness_nm = {:?} }}",
                            l.index, l.thickness_nm
                        )
                    })
                    .collect();
                format!("{{ layers = [{}] }}", layers.join(", "))
            }
        };
        let _ = writeln!(out, "coating = {coating}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const SINGLET: &str = r#"
name = "singlet"
[[surface]]
stop = true
thickness = 2.0
semi_aperture = 5.0
[[surface]]
radius = 50.0
thickness = 6.0
n_d = 1.5
v_d = 60.0
semi_aperture = 8.0
[[surface]]
radius = -80.0
semi_aperture = 8.0
"#;

    #[test]
    fn a_file_round_trips_through_its_text() {
        let lens = Lens::parse(SINGLET, "singlet.toml").unwrap();
        assert_eq!(lens.surfaces[1].coating, Coating::magnesium_fluoride());
        assert_eq!(lens.surfaces[0].coating, Coating::None);
        let again = Lens::parse(&lens.to_toml(), "again.toml").unwrap();
        assert_eq!(again, lens);
    }

    #[test]
    fn an_anamorphic_file_round_trips_through_its_text() {
        let text = SINGLET
            .replacen("radius = 50.0", "radius = 50.0\nradius_y = \"flat\"", 1)
            .replacen("radius = -80.0", "radius = \"flat\"\nradius_y = -80", 1);
        let lens = Lens::parse(&text, "a.toml").unwrap();
        assert_eq!(lens.surfaces[1].radius_y, Some(None));
        assert_eq!(lens.surfaces[2].curvatures(), (0.0, -1.0 / 80.0));
        assert!(lens.is_anamorphic() && lens.surfaces[0].is_round());
        let again = Lens::parse(&lens.to_toml(), "again.toml").unwrap();
        assert_eq!(again, lens);
    }

    #[test]
    fn the_focal_length_scales_the_prescription() {
        let text = SINGLET.replace("name = \"singlet\"", "name = \"x\"\nfocal_length_mm = 25");
        let lens = Lens::parse(&text, "x.toml").unwrap();
        let f = lens.paraxial().unwrap().focal_length;
        assert!((f * lens.mm_per_unit - 25.0).abs() < 1e-9);
        let again = Lens::parse(&lens.to_toml(), "again.toml").unwrap();
        assert!((again.mm_per_unit - lens.mm_per_unit).abs() < 1e-12);
    }

    #[test]
    fn coatings_of_every_form_are_read() {
        let with = |c: &str| {
            let text = SINGLET.replace("v_d = 60.0", &format!("v_d = 60.0\ncoating = {c}"));
            Lens::parse(&text, "c.toml").map(|l| l.surfaces[1].coating.clone())
        };
        assert_eq!(with("\"none\"").unwrap(), Coating::None);
        assert_eq!(
            with("{ index = 1.38 }").unwrap(),
            Coating::magnesium_fluoride()
        );
        assert_eq!(
            with("{ index = 2.0, design_nm = 600 }").unwrap(),
            Coating::quarter_wave(2.0, 600.0)
        );
        let stack = with("{ layers = [{ index = 2.1, thickness_nm = 65 }, { index = 1.38, thickness_nm = 99 }] }")
            .unwrap();
        assert_eq!(
            stack,
            Coating::Layers(vec![
                Layer {
                    index: 2.1,
                    thickness_nm: 65.0
                },
                Layer {
                    index: 1.38,
                    thickness_nm: 99.0
                }
            ])
        );
        let error = with("\"gold\"").unwrap_err().to_string();
        assert!(
            error.starts_with("c.toml:") && error.contains("\"mgf2\""),
            "{error}"
        );
    }

    #[test]
    fn bad_prescriptions_say_which_surface_and_what_is_allowed() {
        let cases = [
            (
                "semi_aperture = 8.0\n[[surface]]\nradius = -80.0",
                "semi_aperture = 90.0\n[[surface]]\nradius = -80.0",
                "exceeds |radius|",
            ),
            ("radius = 50.0", "radius = 0", "\"flat\""),
            (
                "radius = 50.0",
                "radius = 50.0\nradius_y = 0",
                "radius_y = 0 is not allowed",
            ),
            (
                "radius = 50.0",
                "radius = 50.0\nradius_y = 7.0",
                "exceeds |radius_y| = 7",
            ),
            (
                "stop = true",
                "stop = true\nradius_y = 40.0",
                "give it no radius, radius_y",
            ),
            ("n_d = 1.5", "n_d = 4.5", "an index from 1 to 3"),
            (
                "stop = true",
                "stop = false",
                "exactly one surface with stop = true",
            ),
            ("thickness = 6.0", "thickness = -6.0", "0 or more"),
            (
                "semi_aperture = 5.0",
                "semi_aperture = 5.0\nwidth = 3",
                "unknown field",
            ),
        ];
        for (from, to, says) in cases {
            let text = SINGLET.replacen(from, to, 1);
            let error = Lens::parse(&text, "bad.toml").unwrap_err().to_string();
            assert!(
                error.starts_with("bad.toml:") && error.contains(says),
                "{to}: {error}"
            );
            assert_eq!(error.lines().count(), 1, "{error}");
        }
    }

    #[test]
    fn the_index_keeps_n_d_and_the_abbe_number() {
        let glass = Medium::Glass {
            n_d: 1.5168,
            v_d: Some(64.17),
        };
        assert!((glass.index_at(super::super::D_LINE_NM) - 1.5168).abs() < 1e-12);
        let spread =
            glass.index_at(super::super::F_LINE_NM) - glass.index_at(super::super::C_LINE_NM);
        assert!((spread - 0.5168 / 64.17).abs() < 1e-12);
        assert!(glass.index_at(450.0) > glass.index_at(650.0));
    }
}
