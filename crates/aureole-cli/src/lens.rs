//! `aureole lens FILE`: a lens prescription's first-order data and
//! surfaces, from aureole's TOML, pbrt's `.dat` or lentil's JSON; `-o`
//! writes it as aureole's TOML.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

use aureole::lens::{Coating, Lens, Medium, Paraxial};
use aureole_io::lenses::{read_lens, write_lens};

use crate::Failure;

#[derive(clap::Args)]
pub struct Args {
    /// The lens file: .toml (aureole), .dat (pbrt), .json (lentil's database) or .txt (an Optical Bench file of photonstophotos.net); or a shipped lens's name (double-gauss-50mm-f1.4, …)
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
    /// Draw the lens's section through the axis into this picture (SVG)
    #[arg(long, value_name = "OUT.svg")]
    svg: Option<PathBuf>,
    /// Render the ghosts of one distant source into this linear image (.exr, .pfm): R, G and B, each pixel the light it gets over the light of the source's own image
    #[arg(long, value_name = "OUT.exr")]
    ghosts: Option<PathBuf>,
    /// The source's direction, degrees right and up of the axis (for --ghosts)
    #[arg(long, value_name = "X,Y", default_value = "6,4", value_parser = parse_direction)]
    source: (f64, f64),
    /// The stop's f-number (for --ghosts; default: the lens wide open)
    #[arg(long, value_name = "N", value_parser = crate::values::parse_positive)]
    f_number: Option<f64>,
    /// Straight blades of the stop, 3 to 64, or 0 for a round one (for --ghosts)
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = parse_blades)]
    blades: u32,
    /// Trace the ghosts at 17 wavelengths from 380 to 780 nm instead of one per channel (for --ghosts)
    #[arg(long)]
    spectral: bool,
    /// The picture's size in pixels over a 36 mm wide sensor (for --ghosts)
    #[arg(long, value_name = "WxH", default_value = "1440x960", value_parser = crate::values::parse_size)]
    size: (usize, usize),
}

/// A stop's blade count: 0 (round) or 3 to 64.
fn parse_blades(text: &str) -> Result<u32, String> {
    match text.parse::<u32>() {
        Ok(n) if n == 0 || (3..=aureole::optics::aperture::MAX_BLADES).contains(&n) => Ok(n),
        _ => Err(format!(
            "{text:?} is not a blade count: 0 for a round stop, or 3 to 64"
        )),
    }
}

/// "X,Y" in degrees, each within ±80.
fn parse_direction(text: &str) -> Result<(f64, f64), String> {
    let parts: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{text:?} is not two angles in degrees, X,Y (e.g. 6,4)"))?;
    match parts[..] {
        [x, y] if x.abs() <= 80.0 && y.abs() <= 80.0 => Ok((x, y)),
        _ => Err(format!(
            "{text:?}: give two angles X,Y in degrees, each from -80 to 80"
        )),
    }
}

pub fn run(args: &Args, quiet: bool) -> Result<(), Failure> {
    // A shipped lens by its name, where no file has it.
    let shipped = args
        .file
        .to_str()
        .filter(|_| !args.file.exists())
        .and_then(aureole::lens::shipped::find);
    let read = match shipped {
        Some(found) => aureole_io::lenses::LensFile {
            lens: found
                .lens()
                .map_err(|e| Failure::Usage(anyhow::anyhow!("{e}")))?,
            notes: Vec::new(),
        },
        None => read_lens(&args.file, args.id.as_deref())?,
    };
    let lens = read.lens;
    if !quiet {
        for note in &read.notes {
            say!("aureole: note: {}: {note}", args.file.display());
        }
    }
    let paraxial = lens
        .paraxial()
        .map_err(|e| Failure::Usage(anyhow::anyhow!("{}: {e}", args.file.display())))?;
    // Every output's folder before any is written: a refused picture
    // after the lens was written, or after its ghosts were traced, would
    // leave part of the work.
    for out in [&args.output, &args.svg, &args.ghosts]
        .into_iter()
        .flatten()
    {
        aureole_io::job::check_folder(out)?;
    }
    if let Some(out) = &args.ghosts {
        aureole_io::write::check_linear_output(out)?;
    }
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
    if let Some(out) = &args.svg {
        if aureole_io::atomic::same_file(&args.file, out) {
            return Err(aureole_io::Error::OverwritesInput { path: out.clone() }.into());
        }
        aureole_io::lens_drawing::write_svg(out, &lens)?;
    }
    if let Some(out) = &args.ghosts {
        ghosts(args, &lens, out, quiet)?;
    }
    let horizontal = lens
        .paraxial_x()
        .map_err(|e| Failure::Usage(anyhow::anyhow!("{}: {e}", args.file.display())))?;
    let text = if args.json {
        json(&lens, (&paraxial, &horizontal))
    } else if quiet {
        return Ok(());
    } else {
        describe(&lens, (&paraxial, &horizontal))
    };
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
    Ok(())
}

/// What scripts read of a lens: its first-order data (vertical, and the
/// horizontal `_x` ones, which differ for an anamorphic lens) and what its
/// patent states, in the prescription's units (mm × `mm_per_unit`).
fn json(lens: &Lens, (p, x): (&Paraxial, &Paraxial)) -> String {
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
        "focal_length_x": x.focal_length,
        "back_focus_x": x.back_focus,
        "squeeze": p.focal_length / x.focal_length,
    });
    format!("{value:#}\n")
}

/// What a user reads of a lens: its first-order data, what its patent
/// states beside ours, and its surfaces.
fn describe(lens: &Lens, (p, x): (&Paraxial, &Paraxial)) -> String {
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
    let anamorphic = lens.is_anamorphic();
    if anamorphic {
        let _ = writeln!(
            out,
            "anamorphic: across x focal length {:.3} mm, back focus {:.3} mm; a squeeze of {:.3}",
            x.focal_length * mm,
            x.back_focus * mm,
            p.focal_length / x.focal_length
        );
    }
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
        "\n  #       radius{}   thickness      n_d     V_d  semi-aperture  coating",
        if anamorphic { "     radius y" } else { "" }
    );
    let shown = |r: Option<f64>| r.map_or("flat".to_string(), |r| format!("{:.4}", r * mm));
    for (i, s) in lens.surfaces.iter().enumerate() {
        let mut radius = match s.stop {
            true => "stop".to_string(),
            false => shown(s.radius),
        };
        if anamorphic {
            let across_y = match s.stop {
                true => String::new(),
                false => shown(s.radius_y.unwrap_or(s.radius)),
            };
            radius = format!("{radius:>12} {across_y:>12}");
        }
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

/// `--ghosts`: every ghost of the source, rendered and written; the
/// brightest listed.
fn ghosts(args: &Args, lens: &Lens, out: &std::path::Path, quiet: bool) -> Result<(), Failure> {
    use aureole::lens::effect::GhostOptics;
    use aureole::lens::ghost::render;
    use aureole::lens::trace::Path;
    let failed =
        |e: aureole::Error| Failure::Usage(anyhow::anyhow!("{}: {e}", args.file.display()));
    let (width, height) = args.size;
    // A 36 mm wide sensor, the lens at its own focal length.
    let camera = aureole::CameraGeometry {
        sensor_width_mm: Some(36.0),
        f_number: args.f_number,
        ..Default::default()
    };
    // The lens's own squeeze: the stop is an anamorphic lens's too.
    let aperture = aureole::Aperture {
        squeeze: lens.squeeze().map_err(failed)?,
        ..aureole::Aperture::new(args.blades)
    };
    let optics =
        GhostOptics::new(lens, &camera, Some(&aperture), width, args.spectral).map_err(failed)?;
    let f_number = optics.f_number;
    if let Some(n) = args.f_number.filter(|&n| n < f_number && !quiet) {
        say!(
            "aureole: note: {}: f/{n} is wider than the lens opens: its ghosts are traced at f/{f_number:.2}, wide open",
            args.file.display()
        );
    }
    let layout = optics.layout().map_err(failed)?;
    let sensor = optics.sensor((width, height), (0.5 * width as f64, 0.5 * height as f64));
    let field = aureole::lens::ghost::direction(args.source.0, args.source.1);
    let progress = crate::progress::Progress::new(quiet);
    progress.stage("tracing ghosts");
    let cancel = aureole::Cancel::new();
    let mut report = |fraction| progress.set(fraction);
    let rendered = render(
        &layout,
        field,
        &sensor,
        &optics.light,
        &mut aureole::Control::new(&cancel, &mut report),
    )?;
    progress.finish();
    let image = aureole::Image {
        width,
        height,
        layout: aureole::Layout::Rgb,
        planes: rendered
            .planes
            .into_iter()
            .map(|p| p.into_iter().map(|v| v as f32).collect())
            .collect(),
        alpha: None,
        white_luminance: None,
        primaries: None,
    };
    crate::interrupt::writing(|| {
        aureole_io::write::write_linear(out, &image, aureole_io::write::LinearOptions::default())
    })?;
    if !quiet {
        let ranked = &rendered.ranked;
        let total: f64 = ranked.iter().map(|r| r.1).sum();
        say!(
            "wrote {}: {} ghosts of a source at ({}°, {}°), f/{:.2}, together {:.3e} of its image's light; the brightest:",
            out.display(),
            ranked.len(),
            args.source.0,
            args.source.1,
            f_number,
            total
        );
        for (path, light) in ranked.iter().take(5) {
            if let Path::Ghost { first, second } = path {
                say!("  surfaces {} and {}: {light:.3e}", first + 1, second + 1);
            }
        }
    }
    Ok(())
}
