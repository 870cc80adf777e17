//! `aureole lens FILE`: a lens prescription's first-order data and
//! surfaces, from aureole's TOML, pbrt's `.dat` or lentil's JSON; `-o`
//! writes it as aureole's TOML.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

use aureole::lens::{Coating, Lens, Medium};
use aureole_io::lenses::{read_lens, write_lens};

use crate::Failure;

#[derive(clap::Args)]
pub struct Args {
    /// The lens file: .toml (aureole), .dat (pbrt), .json (lentil's database) or .txt (an Optical Bench file of photonstophotos.net)
    file: PathBuf,
    /// The lens of a lentil database to read (its id)
    #[arg(long)]
    id: Option<String>,
    /// Also write the lens as aureole's TOML here (an import's first step)
    #[arg(short, long, value_name = "OUT.toml")]
    output: Option<PathBuf>,
    /// Print the first-order data as JSON (in the prescription's units) instead of the table
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args, quiet: bool) -> Result<(), Failure> {
    let read = read_lens(&args.file, args.id.as_deref())?;
    let lens = read.lens;
    if !quiet {
        for note in &read.notes {
            say!("aureole: note: {}: {note}", args.file.display());
        }
    }
    let paraxial = lens
        .paraxial()
        .map_err(|e| Failure::Usage(anyhow::anyhow!("{}: {e}", args.file.display())))?;
    if let Some(out) = &args.output {
        if out.extension().and_then(|e| e.to_str()) != Some("toml") {
            return Err(Failure::Usage(anyhow::anyhow!(
                "{}: a lens is written as aureole's TOML: name the output .toml",
                out.display()
            )));
        }
        if aureole_io::atomic::same_file(&args.file, out) {
            return Err(aureole_io::Error::OverwritesInput { path: out.clone() }.into());
        }
        write_lens(out, &lens)?;
    }
    let text = if args.json {
        json(&lens, &paraxial)
    } else if quiet {
        return Ok(());
    } else {
        describe(&lens, &paraxial)
    };
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
    Ok(())
}

/// What scripts read of a lens: its first-order data and what its patent
/// states, in the prescription's units (mm × `mm_per_unit`).
fn json(lens: &Lens, p: &aureole::lens::Paraxial) -> String {
    let patent = lens.patent.as_ref().map(|patent| {
        serde_json::json!({
            "number": patent.number,
            "example": patent.example,
            "focal_length": patent.focal_length,
            "back_focus": patent.back_focus,
            "f_number": patent.f_number,
        })
    });
    let value = serde_json::json!({
        "name": lens.name,
        "patent": patent,
        "mm_per_unit": lens.mm_per_unit,
        "surfaces": lens.surfaces.len(),
        "stop": lens.stop() + 1,
        "focal_length": p.focal_length,
        "back_focus": p.back_focus,
        "entrance_pupil": p.entrance_pupil,
        "entrance_pupil_radius": p.entrance_pupil_radius,
        "f_number": p.f_number,
    });
    format!("{value:#}\n")
}

/// What a user reads of a lens: its first-order data, what its patent
/// states beside ours, and its surfaces.
fn describe(lens: &Lens, p: &aureole::lens::Paraxial) -> String {
    let mut out = String::new();
    let mm = lens.mm_per_unit;
    let _ = writeln!(out, "{}", lens.name);
    if let Some(patent) = &lens.patent {
        let _ = writeln!(out, "from {}, {}", patent.number, patent.example);
    }
    let _ = writeln!(
        out,
        "{} surfaces, the stop is surface {}; lengths in mm{}",
        lens.surfaces.len(),
        lens.stop() + 1,
        if mm == 1.0 {
            String::new()
        } else {
            format!(" ({mm:.6} mm per unit of the prescription)")
        }
    );
    let _ = writeln!(
        out,
        "focal length {:.3} mm, back focus {:.3} mm, f/{:.2} wide open; entrance pupil {:.3} mm behind the first vertex, {:.3} mm across",
        p.focal_length * mm,
        p.back_focus * mm,
        p.f_number,
        p.entrance_pupil * mm,
        2.0 * p.entrance_pupil_radius * mm
    );
    if let Some(patent) = &lens.patent {
        for (what, stated, ours) in [
            ("focal length", patent.focal_length, p.focal_length),
            ("back focus", patent.back_focus, p.back_focus),
        ] {
            if let Some(stated) = stated {
                let _ = writeln!(
                    out,
                    "the patent's {what} {stated}, this trace's {ours:.4} ({:+.3} %)",
                    100.0 * (ours / stated - 1.0)
                );
            }
        }
    }
    let _ = writeln!(
        out,
        "\n  #       radius   thickness      n_d     V_d  semi-aperture  coating"
    );
    for (i, s) in lens.surfaces.iter().enumerate() {
        let radius = match (s.stop, s.radius) {
            (true, _) => "stop".to_string(),
            (false, None) => "flat".to_string(),
            (false, Some(r)) => format!("{:.4}", r * mm),
        };
        let (n_d, v_d) = match s.medium {
            Medium::Glass { n_d, v_d } if !s.stop => (
                format!("{n_d:.5}"),
                v_d.map_or("-".to_string(), |v| format!("{v:.2}")),
            ),
            _ => (String::new(), String::new()),
        };
        let coating = match &s.coating {
            Coating::None => "none".to_string(),
            Coating::Layers(layers) => layers
                .iter()
                .map(|l| format!("n {} × {:.1} nm", l.index, l.thickness_nm))
                .collect::<Vec<_>>()
                .join(", "),
        };
        let _ = writeln!(
            out,
            "{:>3} {:>12} {:>11.4} {:>8} {:>7} {:>14.4}  {coating}",
            i + 1,
            radius,
            s.thickness * mm,
            n_d,
            v_d,
            s.semi_aperture * mm
        );
    }
    out
}
