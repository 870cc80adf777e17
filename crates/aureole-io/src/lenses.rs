//! Lens files: aureole's own TOML, pbrt's `.dat` tables, the `lentil`
//! project's JSON database and the PhotonsToPhotos Optical Bench's text
//! files of patent examples, each read into an [`aureole::lens::Lens`];
//! and a lens written back as TOML (what an import becomes).
//!
//! - **pbrt** (`.dat`, pbrt-v3 and v4's realistic camera): `#` comments,
//!   then one line per surface from the front, `radius thickness n
//!   aperture`, in mm: a radius of 0 is the stop, the thickness is the
//!   distance to the next surface (after the last, to the film; 0 where
//!   focusing sets it), n the index after the surface (0 or 1 for air) and
//!   the aperture a diameter. pbrt gives no Abbe numbers, so its glasses
//!   do not disperse until a `v_d` is added to the TOML.
//! - **lentil** (`.json`, `polynomial-optics/database/lenses.json`): an
//!   object of lenses by id, each with `optical-elements-patent` (radius,
//!   thickness, ior, abbe, housing-radius, material, lens-geometry; the
//!   `iris` is the stop), `patent-number` and `focal-length-mm-patent`.
//! - **Optical Bench** (`.txt`, the format of photonstophotos.net's
//!   transcriptions of patent examples): sections `[descriptive data]`
//!   (`title`), `[variable distances]` (`Focal Length`, `Bf`, `Bf(p)` the
//!   patent's own back focus, named gaps), `[lens data]` (one row per
//!   surface: number, radius or `AS` for the stop, thickness or a gap's
//!   name, n_d, clear diameter, V_d) and `[aspherical data]`. Aspheric
//!   surfaces keep their base sphere (said in a note): the paraxial data
//!   are exact, real rays through them differ.

use std::path::Path;

use aureole::lens::{Coating, Lens, Medium, Patent, Surface};

use crate::atomic::write_atomic;
use crate::error::{Error, Result};

/// The lens files this reads, by extension, in words.
pub const KINDS: &str = ".toml (aureole), .dat (pbrt), .json (lentil's database) or .txt (an Optical Bench file of photonstophotos.net)";

/// A lens read from a file, and what the user should know of the reading.
#[derive(Debug, Clone)]
pub struct LensFile {
    /// The lens.
    pub lens: Lens,
    /// What the format could not say or this reader left out, a line each.
    pub notes: Vec<String>,
}

/// Reads the lens in `path`: by its extension, aureole's TOML, pbrt's
/// `.dat`, lentil's JSON (where `id` picks one lens of the database) or
/// an Optical Bench `.txt`.
pub fn read_lens(path: &Path, id: Option<&str>) -> Result<LensFile> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let name = path.display().to_string();
    let decode = |message: String| Error::Decode {
        path: path.to_path_buf(),
        message,
    };
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if id.is_some() && extension != "json" {
        return Err(decode(
            "--id picks a lens of a lentil database (.json); this file holds one lens".into(),
        ));
    }
    let mut notes = Vec::new();
    let lens = match extension.as_str() {
        "toml" => {
            let lens = Lens::parse(&text, &name).map_err(Error::Lens)?;
            return Ok(LensFile { lens, notes });
        }
        "dat" => {
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("lens");
            let (title, surfaces) = pbrt(&text, stem).map_err(decode)?;
            notes.push(
                "pbrt's tables give no Abbe numbers: its glasses do not disperse until each has a v_d"
                    .to_string(),
            );
            Lens::from_surfaces(title, None, surfaces, &name)
        }
        "json" => {
            let (title, patent, surfaces) = lentil(&text, id).map_err(decode)?;
            Lens::from_surfaces(title, patent, surfaces, &name)
        }
        "txt" => {
            let read = optical_bench(&text).map_err(decode)?;
            notes.extend(read.notes);
            Lens::from_surfaces(read.name, Some(read.patent), read.surfaces, &name)
        }
        other => {
            return Err(decode(format!(
                "unknown lens file extension {other:?}; allowed: {KINDS}"
            )))
        }
    };
    let lens = lens.map_err(|e| match e {
        aureole::Error::Lens { message, .. } => decode(message),
        other => decode(other.to_string()),
    })?;
    Ok(LensFile { lens, notes })
}

/// Writes `lens` as aureole's TOML at `path`, atomically.
pub fn write_lens(path: &Path, lens: &Lens) -> Result<()> {
    write_atomic(path, |out| {
        use std::io::Write;
        out.write_all(lens.to_toml().as_bytes())
            .map_err(|e| Error::io(path, e))
    })
}

/// An imported surface's coating: neither format gives one, so the usual
/// single layer of MgF₂ where it separates air from glass.
fn imported_coating(before: Medium, after: Medium) -> Coating {
    Coating::unless_given(before, after, &Coating::magnesium_fluoride())
}

/// A pbrt `.dat` table: its first comment line as the name (else `stem`)
/// and its surfaces.
fn pbrt(text: &str, stem: &str) -> std::result::Result<(String, Vec<Surface>), String> {
    let mut name = None;
    let mut surfaces = Vec::new();
    let mut before = Medium::Air;
    for (number, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(comment) = line.strip_prefix('#') {
            let comment = comment.trim().trim_matches('"').trim();
            if name.is_none() && !comment.is_empty() {
                name = Some(comment.to_string());
            }
            continue;
        }
        if line.is_empty() {
            continue;
        }
        let values: Vec<f64> = line
            .split_whitespace()
            .map(|v| v.trim_matches('"').parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                format!(
                    "line {}: {line:?} is not four numbers: radius thickness n aperture",
                    number + 1
                )
            })?;
        let [radius, thickness, n, aperture] = values[..] else {
            return Err(format!(
                "line {}: {} numbers where pbrt's table has four: radius thickness n aperture",
                number + 1,
                values.len()
            ));
        };
        let stop = radius == 0.0;
        let medium = if stop {
            before
        } else if n == 0.0 || n == 1.0 {
            Medium::Air
        } else {
            Medium::Glass { n_d: n, v_d: None }
        };
        surfaces.push(Surface {
            radius: (!stop).then_some(radius),
            radius_y: None,
            thickness,
            medium,
            semi_aperture: aperture / 2.0,
            coating: imported_coating(before, medium),
            stop,
        });
        before = medium;
    }
    Ok((name.unwrap_or_else(|| stem.to_string()), surfaces))
}

/// One lens of lentil's database: its name, patent and surfaces.
fn lentil(
    text: &str,
    id: Option<&str>,
) -> std::result::Result<(String, Option<Patent>, Vec<Surface>), String> {
    let database: serde_json::Value =
        serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    let lenses = database
        .as_object()
        .ok_or("not a lentil database: an object of lenses by id")?;
    let mut ids: Vec<&String> = lenses.keys().collect();
    ids.sort_by_key(|k| (k.parse::<u64>().unwrap_or(u64::MAX), k.to_string()));
    let listed = || {
        ids.iter()
            .map(|k| {
                let name = lenses[k.as_str()]
                    .get("product-name")
                    .and_then(|v| v.as_str())
                    .unwrap_or("?");
                format!("{k} ({name})")
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let key = match (id, ids.as_slice()) {
        (Some(id), _) => id.to_string(),
        (None, [only]) => only.to_string(),
        (None, _) => {
            return Err(format!(
                "it holds {} lenses: pick one with --id; the ids are {}",
                ids.len(),
                listed()
            ))
        }
    };
    let lens = lenses
        .get(&key)
        .ok_or_else(|| format!("no lens with id {key:?}; the ids are {}", listed()))?;
    let text_of = |field: &str| lens.get(field).and_then(|v| v.as_str()).map(str::to_string);
    let number_of = |v: &serde_json::Value, field: &str| v.get(field).and_then(|x| x.as_f64());
    let elements = lens
        .get("optical-elements-patent")
        .and_then(|v| v.as_array())
        .ok_or_else(|| format!("lens {key} has no optical-elements-patent list"))?;
    let mut surfaces = Vec::with_capacity(elements.len());
    let mut before = Medium::Air;
    for (i, element) in elements.iter().enumerate() {
        let at = |m: &str| format!("lens {key}, element {}: {m}", i + 1);
        let geometry = element
            .get("lens-geometry")
            .and_then(|v| v.as_str())
            .unwrap_or("spherical");
        // lentil's cylinders are named by their axis: "cyl-y" runs along
        // y, so it curves across x (its tracer drops y from the distance
        // to the axis), and "cyl-x" curves across y.
        let curved = match geometry {
            "spherical" => None,
            "cyl-y" => Some(true),
            "cyl-x" => Some(false),
            _ => {
                return Err(at(&format!(
                    "its surface is {geometry}: spherical and cylindrical (cyl-x, cyl-y) surfaces are read, aspheric ones not yet"
                )))
            }
        };
        let material = element
            .get("material")
            .and_then(|v| v.as_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let stop = material == "iris";
        let radius = number_of(element, "radius").ok_or_else(|| at("no radius"))?;
        let thickness = number_of(element, "thickness").ok_or_else(|| at("no thickness"))?;
        let semi_aperture =
            number_of(element, "housing-radius").ok_or_else(|| at("no housing-radius"))?;
        let ior = number_of(element, "ior").unwrap_or(1.0);
        let medium = if stop {
            before
        } else if material == "air" || ior == 1.0 {
            Medium::Air
        } else {
            Medium::Glass {
                n_d: ior,
                v_d: number_of(element, "abbe").filter(|v| *v > 0.0),
            }
        };
        let (radius, radius_y) = match curved {
            _ if stop => (None, None),
            None => (Some(radius), None),
            Some(true) => (Some(radius), Some(None)),
            Some(false) => (None, Some(Some(radius))),
        };
        surfaces.push(Surface {
            radius,
            radius_y,
            thickness,
            medium,
            semi_aperture,
            coating: imported_coating(before, medium),
            stop,
        });
        before = medium;
    }
    let name = [
        text_of("company"),
        text_of("product-name"),
        lens.get("year").map(|y| y.to_string()),
    ]
    .into_iter()
    .flatten()
    .collect::<Vec<_>>()
    .join(" ");
    let patent = text_of("patent-number").map(|number| Patent {
        number,
        example: format!("as lentil's database gives it (lens {key})"),
        focal_length: number_of(lens, "focal-length-mm-patent"),
        back_focus: None,
        f_number: number_of(lens, "fstop"),
    });
    Ok((name, patent, surfaces))
}

/// An Optical Bench file read: its title, the patent it cites with what
/// the file says the patent states, the surfaces, and notes.
struct Bench {
    name: String,
    patent: Patent,
    surfaces: Vec<Surface>,
    notes: Vec<String>,
}

/// A number of an Optical Bench file: `Infinity` is infinite.
fn bench_number(text: &str) -> Option<f64> {
    match text.trim() {
        "Infinity" => Some(f64::INFINITY),
        "-Infinity" => Some(f64::NEG_INFINITY),
        t => t.parse().ok(),
    }
}

fn optical_bench(text: &str) -> std::result::Result<Bench, String> {
    let mut section = String::new();
    let mut title = None;
    let mut number = None;
    let mut example = None;
    let mut distances: Vec<(String, Vec<String>)> = Vec::new();
    let mut rows: Vec<(usize, Vec<String>)> = Vec::new();
    let mut aspheric = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.trim_end_matches('\r');
        if line.trim().is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(name) = line
            .strip_prefix('[')
            .and_then(|l| l.trim().strip_suffix(']'))
        {
            section = name.to_string();
            continue;
        }
        let cells: Vec<String> = line.split('\t').map(|c| c.trim().to_string()).collect();
        let key = cells.first().map(String::as_str).unwrap_or("");
        let value = cells.get(1).cloned().unwrap_or_default();
        match section.as_str() {
            "descriptive data" if key == "title" => title = Some(value),
            "patent info" if key == "number" => number = Some(value),
            "patent info" if key == "example" => example = Some(value),
            "variable distances" => distances.push((key.to_string(), cells[1..].to_vec())),
            "lens data" => rows.push((n + 1, cells)),
            "aspherical data" => aspheric.push(key.to_string()),
            _ => {}
        }
    }
    if section.is_empty() && title.is_none() {
        return Err("not an Optical Bench file: it has no [descriptive data] section".into());
    }
    let title = title.ok_or("its [descriptive data] has no title")?;
    let distance = |name: &str| {
        distances
            .iter()
            .find(|(k, _)| k == name)
            .and_then(|(_, v)| v.first())
            .and_then(|v| bench_number(v))
    };
    let zoom = distances
        .iter()
        .find(|(k, _)| k == "Focal Length")
        .is_some_and(|(_, v)| v.iter().filter(|c| bench_number(c).is_some()).count() > 1);
    let mut notes = Vec::new();
    if zoom {
        notes.push("a zoom: its gaps at the first focal length the file lists".to_string());
    }
    let mut surfaces = Vec::with_capacity(rows.len());
    let mut before = Medium::Air;
    for (line, cells) in &rows {
        let at = |m: &str| format!("line {line}: {m}");
        let cell = |i: usize| cells.get(i).map(String::as_str).unwrap_or("");
        let stop = cell(1) == "AS";
        // A flare stop (FS) or a cover glass's face (CG) is a plane.
        let radius = if stop || matches!(cell(1), "FS" | "CG") {
            None
        } else {
            let r = bench_number(cell(1))
                .ok_or_else(|| at(&format!("radius {:?} is not a number", cell(1))))?;
            r.is_finite().then_some(r)
        };
        let thickness = match bench_number(cell(2)) {
            Some(t) => t,
            None => distance(cell(2)).ok_or_else(|| {
                at(&format!(
                    "the gap {:?} is not in [variable distances]",
                    cell(2)
                ))
            })?,
        };
        let medium = match (stop, bench_number(cell(3))) {
            (true, _) => before,
            (false, Some(n_d)) if n_d > 1.0 => Medium::Glass {
                n_d,
                v_d: bench_number(cell(5)).filter(|v| *v > 0.0),
            },
            _ => Medium::Air,
        };
        let diameter = bench_number(cell(4))
            .filter(|d| d.is_finite() && *d > 0.0)
            .ok_or_else(|| at("no clear diameter (its fifth column)"))?;
        if aspheric.iter().any(|a| a == cell(0)) {
            notes.push(format!(
                "surface {} is aspheric: its base sphere is kept (the paraxial data are exact, real rays through it differ)",
                surfaces.len() + 1
            ));
        }
        surfaces.push(Surface {
            radius,
            radius_y: None,
            thickness,
            medium,
            semi_aperture: diameter / 2.0,
            coating: imported_coating(before, medium),
            stop,
        });
        before = medium;
    }
    // The title reads "US 2,681,594 Example 1 (lens name)" where the file
    // has no [patent info].
    let (cited, named) = match title.split_once(" Example") {
        Some((cited, rest)) => {
            let rest = rest.split('(').next().unwrap_or("").trim();
            (cited.trim().to_string(), format!("Example {rest}"))
        }
        None => (title.clone(), String::new()),
    };
    let example = example.map_or(named, |e| {
        format!("Example {}", e.trim_start_matches("EX "))
    });
    let stated_back = distance("Bf(p)").or_else(|| distance("Bf"));
    Ok(Bench {
        name: title.clone(),
        patent: Patent {
            number: number.unwrap_or(cited),
            example,
            focal_length: distance("Focal Length"),
            back_focus: stated_back,
            f_number: distance("F-Number"),
        },
        surfaces,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const DGAUSS: &str = "# D-GAUSS F/2 22deg HFOV\n# radius\taxpos\tN\taperture\n\
        29.475\t3.76\t1.67\t25.2\n84.83\t0.12\t1\t25.2\n19.275\t4.025\t1.67\t23\n\
        40.77\t3.275\t1.699\t23\n12.75\t5.705\t1\t18\n0\t4.5\t0\t17.1\n\
        -14.495\t1.18\t1.603\t17\n40.77\t6.065\t1.658\t20\n-20.385\t0.19\t1\t20\n\
        437.065\t3.22\t1.717\t20\n-39.73\t0\t1\t20\n";

    #[test]
    fn a_pbrt_table_becomes_a_lens() {
        let (name, surfaces) = pbrt(DGAUSS, "dgauss").unwrap();
        assert_eq!(name, "D-GAUSS F/2 22deg HFOV");
        let lens = Lens::from_surfaces(name, None, surfaces, "dgauss.dat").unwrap();
        assert_eq!(lens.surfaces.len(), 11);
        assert_eq!(lens.stop(), 5);
        assert_eq!(lens.surfaces[5].semi_aperture, 8.55);
        // The cemented pair's inner surface is bare, the air–glass ones coated.
        assert_eq!(lens.surfaces[3].coating, Coating::None);
        assert_eq!(lens.surfaces[0].coating, Coating::magnesium_fluoride());
        // pbrt's 50 mm double-Gauss.
        let f = lens.paraxial().unwrap().focal_length;
        assert!((f - 50.0).abs() < 1.5, "{f}");
    }

    #[test]
    fn a_bad_pbrt_line_is_named() {
        let error = pbrt("# x\n1 2 3\n", "x").unwrap_err();
        assert!(
            error.starts_with("line 2:") && error.contains("four"),
            "{error}"
        );
    }

    #[test]
    fn a_lentil_lens_is_picked_by_its_id() {
        let json = r#"{"7": {"company": "acme", "product-name": "singlet", "year": 1900,
            "patent-number": "US1", "focal-length-mm-patent": 100.0, "fstop": null,
            "optical-elements-patent": [
              {"radius": 99999, "thickness": 2, "ior": 1.0, "abbe": 0, "housing-radius": 5, "material": "iris", "lens-geometry": "spherical"},
              {"radius": 51.7, "thickness": 4, "ior": 1.5168, "abbe": 64.17, "housing-radius": 8, "material": "abbe", "lens-geometry": "spherical"},
              {"radius": -51.7, "thickness": 98, "ior": null, "abbe": null, "housing-radius": 8, "material": "air", "lens-geometry": "spherical"}
            ]}, "8": {}}"#;
        let (name, patent, surfaces) = lentil(json, Some("7")).unwrap();
        assert_eq!(name, "acme singlet 1900");
        let patent = patent.unwrap();
        assert_eq!(
            (patent.number.as_str(), patent.focal_length),
            ("US1", Some(100.0))
        );
        assert!(surfaces[0].stop && surfaces[0].radius.is_none());
        assert_eq!(
            surfaces[1].medium,
            Medium::Glass {
                n_d: 1.5168,
                v_d: Some(64.17)
            }
        );
        let error = lentil(json, None).unwrap_err();
        assert!(
            error.contains("--id") && error.contains("7 (singlet)"),
            "{error}"
        );
        let error = lentil(json, Some("9")).unwrap_err();
        assert!(error.contains("no lens with id \"9\""), "{error}");
    }

    #[test]
    fn lentils_cylinders_curve_across_the_axis_they_are_not_named_by() {
        let json = r#"{"3": {"product-name": "rear-anamorph", "optical-elements-patent": [
              {"radius": 99999, "thickness": 2, "housing-radius": 5, "material": "iris", "lens-geometry": "spherical"},
              {"radius": 136.373, "thickness": 2.444, "ior": 1.816, "abbe": 46.62, "housing-radius": 14, "material": "SLAH59", "lens-geometry": "cyl-y"},
              {"radius": -176.528, "thickness": 5, "ior": null, "housing-radius": 14, "material": "air", "lens-geometry": "cyl-x"},
              {"radius": 50, "thickness": 5, "ior": 1.5, "housing-radius": 14, "material": "x", "lens-geometry": "aspherical"}
            ]}}"#;
        let error = lentil(json, None).unwrap_err();
        assert!(
            error.contains("element 4") && error.contains("aspherical"),
            "{error}"
        );
        let cut = json.replacen("aspherical", "spherical", 1);
        let (_, _, surfaces) = lentil(&cut, None).unwrap();
        assert_eq!(
            (surfaces[1].radius, surfaces[1].radius_y),
            (Some(136.373), Some(None))
        );
        assert_eq!(
            (surfaces[2].radius, surfaces[2].radius_y),
            (None, Some(Some(-176.528)))
        );
        assert!(surfaces[3].is_round() && surfaces[0].stop);
    }
}
