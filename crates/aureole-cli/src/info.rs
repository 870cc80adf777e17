//! `aureole info`: what an image holds, in luminance.

use std::path::PathBuf;

use aureole::FrameOptions;
use aureole_io::limits::Limits;

use crate::input::SourceArgs;
use crate::{input, Failure};

#[derive(clap::Args)]
pub struct Args {
    /// The image to describe.
    input: PathBuf,

    /// Count the pixels above this luminance in cd/m² (default: a ladder
    /// from 1 to 10⁵).
    #[arg(long, value_name = "CD_PER_M2")]
    threshold: Option<f64>,

    #[command(flatten)]
    source: SourceArgs,
}

pub fn run(args: &Args, quiet: bool) -> Result<(), Failure> {
    let options = FrameOptions {
        input_scale: args.source.input_scale,
        sanitize: false,
    };
    let limits = Limits::default_for_machine();
    let choice = args.source.choice();
    let mut loaded = match aureole_io::read::read_image_with(&args.input, limits, &choice) {
        Ok(loaded) => loaded,
        Err(error) => return describe_refused(args, limits, &choice, error),
    };
    let format = loaded.format;
    let structure = loaded.original.describe();
    // info describes NaN and infinite samples (counted as 0) instead of
    // refusing the file.
    let mut non_finite = 0;
    for v in loaded.image.planes.iter_mut().flatten() {
        if !v.is_finite() {
            *v = 0.0;
            non_finite += 1;
        }
    }
    let frame = input::read_loaded(&args.input, loaded, &options, quiet)?.frame;
    let image = frame.image();
    let mut luminance: Vec<f64> = image
        .luminance()
        .iter()
        .map(|&y| f64::from(y) * frame.scale())
        .collect();
    let above = |t: f64| luminance.iter().filter(|&&y| y > t).count();
    let thresholds: Vec<f64> = match args.threshold {
        Some(t) => vec![t],
        None => vec![1.0, 10.0, 100.0, 1e3, 1e4, 1e5],
    };
    let counts: Vec<String> = thresholds
        .iter()
        .map(|&t| format!("  above {t} cd/m²: {} px", above(t)))
        .collect();
    luminance.sort_by(f64::total_cmp);
    let negatives = image.planes.iter().flatten().filter(|v| **v < 0.0).count();
    let mut text = format!(
        "{}: {} {}x{}, {:?}{}\n",
        args.input.display(),
        format,
        image.width,
        image.height,
        image.layout,
        if image.alpha.is_some() {
            " + alpha"
        } else {
            ""
        }
    );
    for line in structure {
        text += &line;
        text.push('\n');
    }
    text += &format!(
        "scale: {} cd/m² per unit ({})\n",
        frame.scale(),
        input::scale_source(frame.scale_source())
    );
    if image.layout == aureole::Layout::Rgb {
        let [wr, wg, wb] = image.luminance_weights();
        let source = match image.primaries.map(|p| p.luminance_weights()) {
            Some(Some(_)) => "the file's chromaticities",
            Some(None) => "Rec.709: the file's chromaticities are degenerate",
            None => "Rec.709",
        };
        // ACES AP0 weighs blue negatively: "− 0.07213 B", not "+ -0.07213 B".
        let term = |w: f32, c: char| {
            let sign = if w < 0.0 { '−' } else { '+' };
            format!(" {sign} {:.5} {c}", w.abs())
        };
        text += &format!(
            "luminance: Y = {wr:.5} R{}{} ({source})\n",
            term(wg, 'G'),
            term(wb, 'B')
        );
    }
    if let (Some(min), Some(max)) = (luminance.first(), luminance.last()) {
        text += &format!(
            "luminance (cd/m²): min {min:.6} median {:.6} max {max:.6}\n",
            luminance[luminance.len() / 2]
        );
    }
    text += &format!("negative samples: {negatives}\n");
    if non_finite > 0 {
        text += &format!("NaN or infinite samples: {non_finite} (counted as 0)\n");
    }
    text += &counts.join("\n");
    text.push('\n');
    // A closed pipe (`aureole info … | head`) is not an error worth a message.
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes());
    Ok(())
}

/// A file that could not be read: if its headers say why apply cannot
/// spread it (deep data, no single colour layer), its parts, views, layers
/// and channels are described from them with the reason; a damaged file,
/// whose headers do not refuse it, is refused with `error`.
fn describe_refused(
    args: &Args,
    limits: Limits,
    choice: &aureole_io::read::Choice,
    error: aureole_io::Error,
) -> Result<(), Failure> {
    let Err(refused) = aureole_io::read::probe(&args.input, limits, choice) else {
        return Err(error.into());
    };
    let Some(lines) = aureole_io::read::exr_structure(&args.input) else {
        return Err(refused.into());
    };
    let reason = match &refused {
        aureole_io::Error::Decode { message, .. } => message.clone(),
        other => other.to_string(),
    };
    let mut text = format!(
        "{}: OpenEXR; apply cannot spread it: {reason}\n",
        args.input.display()
    );
    for line in lines {
        text += &line;
        text.push('\n');
    }
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes());
    Ok(())
}
