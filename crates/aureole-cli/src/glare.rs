//! `aureole glare`: the glare figures of a view (E_v, DGP, DGI, UGR, VCP,
//! CGI and the glare sources), as Radiance's `evalglare` reports them.

use std::path::{Path, PathBuf};

use anyhow::anyhow;
use aureole::rating::{self, Rating, RatingOptions, Task, Threshold};
use aureole::{Cancel, Projection, View};
use aureole_io::display;
use aureole_io::limits::Limits;
use aureole_io::rating as rated;

use crate::input::SourceArgs;
use crate::values::parse_positive;
use crate::{input, interrupt, Failure};

#[derive(clap::Args)]
pub struct Args {
    /// The view to rate: an HDR picture in cd/m² (a Radiance picture in
    /// Radiance's units), a fisheye or a perspective view.
    input: PathBuf,

    /// The view's Radiance options, as rpict takes them ("-vta -vh 180 -vv
    /// 180"). Default: the picture's VIEW= header line.
    #[arg(long, value_name = "OPTIONS", allow_hyphen_values = true, conflicts_with_all = ["projection", "fov"])]
    view: Option<String>,

    /// The picture's projection, for a picture without a VIEW header (an
    /// EXR from a fisheye lens or a renderer).
    #[arg(long, value_name = "NAME", requires = "fov", value_parser = projection_name)]
    projection: Option<Projection>,

    /// Field of view across the picture, degrees (and down it, unless
    /// --fov-vertical says otherwise).
    #[arg(long, value_name = "DEG", value_parser = parse_positive)]
    fov: Option<f64>,

    /// Field of view down the picture, degrees.
    #[arg(long, value_name = "DEG", requires = "fov", value_parser = parse_positive)]
    fov_vertical: Option<f64>,

    /// A pixel brighter than this luminance, cd/m², is a glare source
    /// (evalglare's -b above 100). Default: 2000, or 5× the task's.
    #[arg(long, value_name = "CD_PER_M2", value_parser = parse_positive, conflicts_with = "multiple")]
    threshold: Option<f64>,

    /// A pixel brighter than this multiple of the task's luminance (or the
    /// view's mean without a task) is a glare source (evalglare's -b).
    #[arg(long, value_name = "FACTOR", value_parser = parse_positive)]
    multiple: Option<f64>,

    /// A task area: column and row of its centre (from the top left) and
    /// its full opening angle in radians (evalglare's -t, whose row counts
    /// from the bottom).
    #[arg(long, num_args = 3, value_names = ["COLUMN", "ROW", "ANGLE"])]
    task: Option<Vec<f64>>,

    /// evalglare's search radius -r, radians: source pixels within half of
    /// it are one source.
    #[arg(long, value_name = "RAD", default_value_t = 0.2, value_parser = parse_positive)]
    search: f64,

    /// Pixels at least this bright are split off into sources of their own
    /// (evalglare's -Y).
    #[arg(long, value_name = "CD_PER_M2", default_value_t = 50_000.0, value_parser = parse_positive)]
    peak: f64,

    /// Keep the peaks in their sources (evalglare's -x).
    #[arg(long, conflicts_with = "peak")]
    no_peak: bool,

    /// Print the figures and sources as JSON, for scripts.
    #[arg(long)]
    json: bool,

    /// Write the view tone-mapped with each glare source marked in its own
    /// colour (PNG, JPEG or TIFF), as evalglare -c does.
    #[arg(long, short = 'c', value_name = "PICTURE")]
    picture: Option<PathBuf>,

    #[command(flatten)]
    source: SourceArgs,
}

fn projection_name(text: &str) -> Result<Projection, String> {
    Projection::from_name(text).ok_or_else(|| {
        let names: Vec<&str> = Projection::ALL.iter().map(|(_, n)| *n).collect();
        format!(
            "{text:?} is not a projection; allowed: {}",
            names.join(", ")
        )
    })
}

/// The view given on the command line, if any, and the option it came
/// from.
fn given_view(args: &Args) -> Result<Option<(View, &'static str)>, Failure> {
    let usage = |e: aureole::Error| Failure::Usage(anyhow!("{}: {e}", args.input.display()));
    if let Some(text) = &args.view {
        return View::from_radiance(text)
            .map(|v| Some((v, "--view")))
            .map_err(usage);
    }
    Ok(match (args.projection, args.fov) {
        (Some(projection), Some(fov)) => {
            let mut view = View::new(projection, fov);
            view.vertical_deg = args.fov_vertical.unwrap_or(fov);
            Some((view, "--projection"))
        }
        _ => None,
    })
}

fn options(args: &Args) -> RatingOptions {
    let task = match args.task.as_deref() {
        Some(&[column, row, angle]) => Some(Task { column, row, angle }),
        _ => None,
    };
    let threshold = match (args.threshold, args.multiple) {
        (Some(l), _) => Some(Threshold::Luminance(l)),
        (None, Some(m)) => Some(Threshold::Multiple(m)),
        (None, None) => None,
    };
    RatingOptions {
        threshold,
        task,
        search_angle: args.search,
        peak_limit: (!args.no_peak).then_some(args.peak),
    }
}

pub fn run(args: &Args, quiet: bool) -> Result<(), Failure> {
    let limits = Limits::default_for_machine();
    let mut loaded = aureole_io::read::read_image_with(&args.input, limits, &args.source.choice())
        .map_err(|e| input::failure(&args.input, e))?;
    let radiance = loaded.original.is_radiance();
    let frame_options = rated::frame_options(&mut loaded, args.source.input_scale);
    let view = rated::view_of(&loaded.original, given_view(args)?).ok_or_else(|| {
        Failure::Usage(anyhow!(
            "{}: the picture says nothing of its view (no VIEW= header line): give --view \"-vta -vh 180 -vv 180\", or --projection equisolid --fov 180",
            args.input.display()
        ))
    })?;
    let (view, view_source) =
        view.map_err(|e| Failure::Usage(anyhow!("{}: {e}", args.input.display())))?;
    let frame = input::read_loaded(&args.input, loaded, &frame_options, quiet)?.frame;
    let options = options(args);
    let rating = rating::rate(
        frame.image(),
        frame.scale(),
        &view,
        &options,
        &Cancel::new(),
    )
    .map_err(|e| input::about(&args.input, e))?;
    if let Some(path) = &args.picture {
        aureole_io::write::refuse_overwrite(path, &args.input)?;
        let picture = rated::marked(&frame, &rating);
        interrupt::writing(|| {
            aureole_io::write::write_picture(path, &picture, display::Depth::Eight)
        })?;
    }
    let scale_source = rated::scale_words(radiance, args.source.input_scale)
        .unwrap_or_else(|| input::scale_source(frame.scale_source()));
    let text = if args.json {
        let mut value = serde_json::to_value(&rating).map_err(|e| Failure::Run(e.into()))?;
        value["file"] = serde_json::json!(args.input.display().to_string());
        value["scale"] = serde_json::json!(frame.scale());
        format!(
            "{}\n",
            serde_json::to_string_pretty(&value).map_err(|e| Failure::Run(e.into()))?
        )
    } else {
        describe(
            &args.input,
            &rating,
            view_source,
            frame.scale(),
            scale_source,
        )
    };
    // A closed pipe (`aureole glare … | head`) is not an error worth a message.
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes());
    Ok(())
}

/// The DGP's class (Wienold 2009's bands).
fn dgp_class(dgp: f64) -> &'static str {
    match dgp {
        d if d < 0.35 => "imperceptible (below 0.35)",
        d if d < 0.40 => "perceptible (0.35 to 0.40)",
        d if d < 0.45 => "disturbing (0.40 to 0.45)",
        _ => "intolerable (0.45 and above)",
    }
}

/// The figures for a person.
fn describe(path: &Path, r: &Rating, view_source: &str, scale: f64, scale_source: &str) -> String {
    let mut text = format!(
        "{}: {}x{}, {} ({view_source}), {scale} cd/m² per unit ({scale_source})\n",
        path.display(),
        r.width,
        r.height,
        r.view
    );
    text += &format!(
        "vertical illuminance E_v {:.1} lx, {:.1} lx of it from the sources\n",
        r.vertical_illuminance, r.direct_illuminance
    );
    text += &format!(
        "luminance: mean {:.2} cd/m², background {:.2} cd/m², brightest {:.4e} cd/m²; sources above {:.1} cd/m²{}\n",
        r.mean_luminance,
        r.background_luminance,
        r.max_luminance,
        r.threshold,
        r.task_luminance
            .map(|t| format!(" (task {t:.2} cd/m²)"))
            .unwrap_or_default()
    );
    text += &format!("DGP {:.3}: {}\n", r.dgp, dgp_class(r.dgp));
    text += &format!(
        "DGI {:.2}  UGR {:.2}  VCP {:.1} %  CGI {:.2}  veiling luminance {:.2} cd/m²\n",
        r.dgi, r.ugr, r.vcp, r.cgi, r.veiling_luminance
    );
    text += &format!(
        "{} glare source{}{}\n",
        r.sources.len(),
        if r.sources.len() == 1 { "" } else { "s" },
        if r.sources.is_empty() {
            ""
        } else {
            ", the brightest first:"
        }
    );
    if !r.sources.is_empty() {
        text += "   #   luminance cd/m²  solid angle sr  position index  off axis  E lx     pixels  at (column, row)\n";
    }
    for (i, s) in r.sources.iter().enumerate() {
        text += &format!(
            "  {:>2}  {:>15.1}  {:>14.6}  {:>14.3}  {:>7.2}°  {:>7.1}  {:>6}  ({:.1}, {:.1})\n",
            i + 1,
            s.luminance,
            s.solid_angle,
            s.position_index,
            s.angle_deg,
            s.illuminance,
            s.pixels,
            s.position[0],
            s.position[1]
        );
    }
    text
}
