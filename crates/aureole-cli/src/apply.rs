//! `aureole apply`: what the camera would have recorded.

use std::path::PathBuf;
use std::time::Instant;

use aureole::io::read::read_image;
use aureole::{ApplyOptions, Config, Kernel, Method, Plan};
use clap::ArgMatches;

use crate::chain::ChainArgs;
use crate::display_args::{parse_positive, DisplayArgs};
use crate::progress::Progress;
use crate::{input, output, Failure};

#[derive(clap::Args)]
#[command(
    after_help = "The output's extension chooses what is written: .exr, .hdr and .pfm stay \
linear, in the input's own units (so the result composites back over the original); .png, .jpg \
and .tif are pictures for a display (exposure, tone curve, sRGB). Without --preset or --config \
the default camera (preset paper-fig5-both) is used."
)]
pub struct Args {
    /// The HDR image: OpenEXR, Radiance .hdr, PFM, or PNG, JPEG, TIFF.
    input: PathBuf,

    /// Where to write the result (.exr, .hdr, .pfm, .png, .jpg, .tif).
    #[arg(short, long, value_name = "OUTPUT")]
    output: PathBuf,

    #[command(flatten)]
    chain: ChainArgs,

    /// Use this kernel (a .pfm or .exr written by `aureole psf`, centre at
    /// its middle) instead of building one from presets and configs: build
    /// it once, apply it to every frame.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["preset", "config", "seed", "max_kernel"])]
    kernel: Option<PathBuf>,

    /// Luminance threshold in cd/m²: pixels at or below it keep their light
    /// in place (overrides the config's `threshold`; 0 spreads every pixel).
    #[arg(long, value_name = "CD_PER_M2", value_parser = parse_non_negative)]
    threshold: Option<f64>,

    /// Soft knee above the threshold, relative to it: the spread fraction
    /// rises smoothly from T to T·(1 + KNEE). 0 is the paper's hard threshold.
    #[arg(long, value_name = "KNEE", default_value = "0", value_parser = parse_non_negative)]
    knee: f64,

    /// cd/m² per file unit. Default: the EXR whiteLuminance attribute if the
    /// file has one, else 1 (the file holds cd/m²).
    #[arg(long, value_name = "X", value_parser = parse_positive)]
    input_scale: Option<f64>,

    /// Replace NaN and infinite pixels by 0 (with a warning) instead of refusing the file.
    #[arg(long)]
    sanitize: bool,

    /// Write only the light the camera adds (result − input), to add over
    /// the original in compositing.
    #[arg(long)]
    glare_only: bool,

    /// How to spread the bright pixels: auto picks by a cost estimate; fft
    /// costs the same however many are bright; splat adds the kernel at
    /// each one (fast for a few hundred lights or a small --max-kernel).
    #[arg(long, value_enum, default_value = "auto")]
    method: MethodArg,

    /// Store EXR output as half floats instead of float32.
    #[arg(long)]
    half: bool,

    /// Cap the kernel's extent in pixels (W or WxH); by default light from
    /// any pixel reaches the whole frame: (2W-1)x(2H-1).
    #[arg(long, value_name = "W[xH]", value_parser = crate::psf::parse_size)]
    max_kernel: Option<(usize, usize)>,

    #[command(flatten)]
    display: DisplayArgs,
}

fn parse_non_negative(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 0.0)
        .ok_or_else(|| format!("{text:?} is not a finite number of at least 0"))
}

pub fn run(args: &Args, matches: &ArgMatches, quiet: bool) -> Result<(), Failure> {
    output::check(&args.output, Some(&args.input))?;
    let (config, defaulted) = match &args.kernel {
        Some(_) => (Config::default(), false),
        None => args.chain.compose_or_default(matches)?,
    };
    let start = Instant::now();
    let input = input::read(&args.input, args.input_scale, args.sanitize, quiet)?;
    let image = &input.loaded.image;
    if !quiet {
        if defaulted {
            eprintln!(
                "aureole: note: no --preset or --config: using the default camera, preset {}",
                aureole::presets::DEFAULT_PRESET
            );
        }
        eprintln!(
            "aureole: note: {}: luminance scale {} cd/m² per unit ({})",
            args.input.display(),
            input.scale,
            input.scale_source
        );
    }
    let progress = Progress::new(quiet);
    progress.stage("building kernel");
    let plan = match &args.kernel {
        Some(path) => {
            let file = read_image(path)?.image;
            let kernel = Kernel::from_planes(file.width, file.height, file.planes)
                .map_err(|e| Failure::Usage(anyhow::anyhow!("{}: {e}", path.display())))?;
            Plan::from_kernel(kernel, image.width, image.height)
        }
        None => Plan::new(&config, image.width, image.height, args.max_kernel)?,
    };
    progress.stage("convolving");
    let options = ApplyOptions {
        threshold: args.threshold.unwrap_or(config.threshold),
        knee: args.knee,
        scale: input.scale,
        glare_only: args.glare_only,
        method: match args.method {
            MethodArg::Auto => Method::Auto,
            MethodArg::Fft => Method::Fft,
            MethodArg::Splat => Method::Splat,
        },
    };
    let applied = plan.apply(image, &options, &mut |f| progress.set(f))?;
    progress.stage("writing");
    let shown = output::write(
        &args.output,
        &applied.image,
        input.scale,
        &args.display,
        args.half,
        quiet,
    )?;
    progress.finish();
    if !quiet {
        let kernel = plan.kernel();
        let ratio = if applied.energy_in != 0.0 {
            format!("{:.4} %", 100.0 * applied.energy_out / applied.energy_in)
        } else {
            "-".to_string()
        };
        eprintln!(
            "wrote {}: {}x{} {:?}, kernel {}x{}, {} px above {} cd/m² ({}), energy in {:.6e} out {:.6e} ({ratio}){}, {:.2} s",
            args.output.display(),
            image.width,
            image.height,
            image.layout,
            kernel.width(),
            kernel.height(),
            applied.spread_pixels,
            options.threshold,
            match applied.method {
                Method::Splat => "splatted",
                _ => "FFT",
            },
            applied.energy_in,
            applied.energy_out,
            shown.map(|s| format!(", {s}")).unwrap_or_default(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum MethodArg {
    Auto,
    Fft,
    Splat,
}
