//! `aureole psf`: build the kernel of the configured optical chain and write it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use aureole::{Cancel, Composing, Control, Extent, Sending};
use aureole_io::formats::{by_extension, extension, kernel_outputs, KernelStorage};
use aureole_io::kernel::{write_kernel_for, KernelRecord};
use clap::{ArgMatches, ValueEnum};

use crate::chain::ChainArgs;
use crate::device::DeviceArg;
use crate::progress::Progress;
use crate::values::{parse_memory, parse_positive, parse_size};
use crate::Failure;

#[derive(clap::Args)]
#[command(
    after_help = "Presets and config files compose in the order given: later settings \
replace earlier ones and effects are appended to the optical chain, which composes by \
convolution. The kernel is normalised over the pixels it writes (ΣK = 1), its centre at \
column floor(W/2) and row floor(H/2) counted from the top."
)]
pub struct Args {
    #[command(flatten)]
    chain: ChainArgs,

    /// Kernel extent in pixels: W (square) or WxH. An image of W×H pixels
    /// needs (2W-1)x(2H-1) for light to reach across the whole frame.
    #[arg(long, value_name = "W[xH]", value_parser = parse_size, required_unless_present = "for_image")]
    size: Option<(usize, usize)>,

    /// The image (a frame of the sequence) the kernel is for: the kernel
    /// `apply` builds for it, (2W-1)x(2H-1) for W×H pixels at the pitch of
    /// W (instead of --size and --image-width). `apply --kernel` with it
    /// gives the same bytes as `apply` building it.
    #[arg(long, value_name = "IMAGE", conflicts_with_all = ["size", "image_width"])]
    for_image: Option<PathBuf>,

    /// Width in pixels of the image the kernel is meant for: sets the pixel
    /// pitch (sensor width / image width) that turns µm and mm into pixels.
    /// Default: the kernel's width.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    image_width: Option<u32>,

    #[arg(short, long, value_name = "OUT", help = format!(
        "Output file: {}; a picture spans 6 decades",
        aureole_io::formats::kernel_outputs()
    ))]
    output: PathBuf,

    /// Also draw the radial profile and the angular profile into this PNG.
    #[arg(long, value_name = "PLOT.png")]
    profile: Option<PathBuf>,

    /// A measured PSF (a photographed star or pinhole, a design program's
    /// PSF) to add to the chain, as `[[effect]] type = "image"`; its pixel
    /// pitch is --pitch-um. Says what it found: its centre, background and
    /// noise, and the light kept above the floor.
    #[arg(long, value_name = "FILE", requires = "pitch_um")]
    from_image: Option<PathBuf>,

    /// Where the effects convolve one another (an optical chain, a star
    /// filter's orders): `auto` takes a hardware GPU where there is one,
    /// else the CPU; `gpu` insists (a software adapter too) and stops
    /// without one. A composition the GPU cannot hold runs on the CPU. A
    /// kernel composed on a GPU differs from the CPU's in the last bits.
    #[arg(long, value_enum, default_value_t = DeviceArg::Auto)]
    device: DeviceArg,

    /// Stop before building when the kernel would need more memory than
    /// this (e.g. 4G, 512M). Default: three quarters of the memory
    /// available when the run starts.
    #[arg(long, value_name = "SIZE", value_parser = parse_memory)]
    max_memory: Option<u64>,

    /// The pixel pitch of --from-image on the sensor, µm.
    #[arg(long, value_name = "UM", requires = "from_image", value_parser = parse_positive)]
    pitch_um: Option<f64>,

    /// Also draw the first aperture's pupil into this PNG, 512 px square:
    /// the light each point passes, white on black, dust, scratches and
    /// grease included.
    #[arg(long, value_name = "PUPIL.png")]
    pupil: Option<PathBuf>,

    /// What sends the light: `pixel`, a pixel of an image, whose light
    /// leaves its whole square (the kernel `apply` convolves with; a 4K
    /// frame reduced to 1080p then looks as the 1080p frame), or `point`,
    /// a point of light (the PSF as an optics program computes it or a
    /// photographed star shows it).
    #[arg(long, value_name = "FROM", value_enum, default_value_t = SentBy::Pixel)]
    sent_by: SentBy,

    /// Radius in pixels of the angular profile (default: a quarter of the
    /// kernel's smaller half-size).
    #[arg(long, value_name = "PX", requires = "profile", value_parser = parse_positive, allow_negative_numbers = true)]
    profile_radius: Option<f64>,
}

/// The width and height of the image at `path`: from its header where the
/// format says them there, else by reading it (which says what is wrong
/// with a file that cannot be read).
fn image_size(path: &Path) -> Result<(usize, usize), Failure> {
    let limits = aureole_io::limits::Limits::default_for_machine();
    let choice = aureole_io::formats::Choice::default();
    if let Some(shape) = aureole_io::read::probe(path, limits, &choice)? {
        return Ok((shape.width, shape.height));
    }
    let loaded = aureole_io::read::read_image_with(path, limits, &choice)?;
    Ok((loaded.image.width, loaded.image.height))
}

/// What sends the light a kernel spreads.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum SentBy {
    Pixel,
    Point,
}

/// The side of a pupil picture, px.
const PUPIL_SIDE: u32 = 512;

pub fn run(args: &Args, matches: &ArgMatches, quiet: bool) -> Result<(), Failure> {
    let holds_kernels =
        by_extension(&args.output).is_some_and(|f| f.kernels != KernelStorage::Unsupported);
    check_output(&args.output, holds_kernels, kernel_outputs())?;
    if let Some(plot) = &args.profile {
        check_output(plot, extension(plot) == "png", ".png".into())?;
    }
    if let Some(picture) = &args.pupil {
        check_output(picture, extension(picture) == "png", ".png".into())?;
    }
    let mut config = args.chain.compose(matches, quiet)?;
    if let (Some(file), Some(pitch)) = (&args.from_image, args.pitch_um) {
        let mut measured = aureole::Measured::new(file.to_string_lossy().into_owned(), pitch);
        let limits = aureole_io::limits::Limits::default_for_machine();
        let (picture, warning) = aureole_io::measured::read_picture(file, limits)?;
        measured.load(picture);
        if let (Some(warning), false) = (warning, quiet) {
            say!("aureole: warning: {warning}");
        }
        let survey = measured.survey()?;
        if !quiet {
            say!("{}", describe(file, &measured, &survey));
        }
        config.effects.push(aureole::Effect::Image(measured));
    }
    if config.effects.is_empty() {
        return Err(aureole::Error::NoEffect.into());
    }
    let optics = match &args.pupil {
        Some(_) => Some(
            aureole::optics::aperture::first_optics(&config)?.ok_or(aureole::Error::NoAperture)?,
        ),
        None => None,
    };
    let mut extent = match (&args.for_image, args.size) {
        (Some(image), _) => {
            let (width, height) = image_size(image)?;
            Extent::for_image(width, height)?
        }
        (None, Some((width, height))) => Extent::new(width, height)?,
        (None, None) => {
            return Err(Failure::Usage(anyhow::anyhow!(
                "psf needs --size W[xH] or --for-image IMAGE"
            )))
        }
    }
    .sent_by(match args.sent_by {
        SentBy::Pixel => Sending::Pixel,
        SentBy::Point => Sending::Point,
    });
    if let Some(n) = args.image_width {
        extent = extent.with_image_width(n as usize);
    }

    check_memory(args, &config, &extent)?;
    let mut composing = Composing::on(args.device.into())?;
    let start = Instant::now();
    let progress = Progress::new(quiet);
    progress.stage("building kernel");
    let cancel = Cancel::new();
    let mut report = |fraction| progress.set(fraction);
    let kernel = config.kernel_on(
        &extent,
        &mut composing,
        &mut Control::new(&cancel, &mut report),
    )?;
    let built = start.elapsed().as_secs_f64();
    progress.stage("writing");
    crate::interrupt::writing(|| {
        write_kernel_for(
            &args.output,
            &kernel,
            KernelRecord {
                image_width: Some(extent.image_width),
                threshold: Some(config.threshold),
                ..KernelRecord::default()
            },
        )
    })?;
    if let Some(plot) = &args.profile {
        let (cx, cy) = kernel.centre();
        let radius = args
            .profile_radius
            .unwrap_or_else(|| (cx.min(cy) as f64 / 4.0).max(1.0));
        crate::interrupt::writing(|| aureole_io::plot::write_profile_plot(plot, &kernel, radius))?;
    }
    if let (Some(picture), Some(optics)) = (&args.pupil, &optics) {
        crate::interrupt::writing(|| {
            aureole_io::plot::write_pupil_picture(picture, optics, PUPIL_SIDE)
        })?;
    }
    progress.finish();
    if !quiet {
        say!("{}", summary(args, &kernel, &composing, built, start));
    }
    Ok(())
}

/// Refuses, before anything large is allocated (as apply refuses a
/// frame), a kernel whose estimated peak is beyond --max-memory.
fn check_memory(args: &Args, config: &aureole::Config, extent: &Extent) -> Result<(), Failure> {
    let limit = args
        .max_memory
        .unwrap_or_else(aureole_io::limits::default_memory_limit);
    let mut needed =
        aureole::memory::Workload::of_kernel(config, extent).estimate_kernel(&config.effects);
    if !matches!(args.device, DeviceArg::Cpu) {
        needed.bytes += aureole::memory::GPU_DRIVERS;
    }
    if needed.bytes > limit {
        return Err(Failure::Run(anyhow::anyhow!(
            "a {}x{} kernel needs about {} (peak while {}) but --max-memory is {}; ask for a smaller --size, or raise --max-memory",
            extent.width,
            extent.height,
            aureole::memory::format_bytes(needed.bytes),
            needed.stage,
            aureole::memory::format_bytes(limit)
        )));
    }
    Ok(())
}

/// The line that says what was written.
fn summary(
    args: &Args,
    kernel: &aureole::Kernel,
    composing: &Composing,
    built: f64,
    start: Instant,
) -> String {
    let sums: Vec<String> = (0..kernel.planes().len())
        .map(|c| format!("{:.6}", kernel.sum(c)))
        .collect();
    format!(
        "wrote {}: {}x{} kernel, {} channel{}, sum {}, centre at column {} row {}, built in {:.2} s{}, {:.2} s in all",
        args.output.display(),
        kernel.width(),
        kernel.height(),
        kernel.planes().len(),
        if kernel.is_coloured() { "s" } else { "" },
        sums.join(" "),
        kernel.centre().0,
        kernel.centre().1,
        built,
        composing
            .words()
            .map(|words| format!(" (composed on {words})"))
            .unwrap_or_default(),
        start.elapsed().as_secs_f64()
    )
}

/// What `psf --from-image` found in its picture, in a line.
fn describe(
    file: &Path,
    measured: &aureole::Measured,
    survey: &aureole::optics::measured::Survey,
) -> String {
    let (w, h) = measured
        .picture
        .as_ref()
        .map_or((0, 0), |p| (p.width, p.height));
    let planes: Vec<String> = survey
        .background
        .iter()
        .zip(&survey.kept)
        .map(|((black, sigma), kept)| {
            format!("black {black:.4} ± {sigma:.4}, {:.1} % kept", 100.0 * kept)
        })
        .collect();
    format!(
        "{}: {w}x{h}, centre at ({:.2}, {:.2}); {} (floor {} σ)",
        file.display(),
        survey.centre[0],
        survey.centre[1],
        planes.join("; "),
        measured.floor
    )
}

/// Refuses an output whose extension we do not write, or whose folder is
/// missing or cannot be written, before any work is done; `listed` names
/// the extensions we write.
fn check_output(path: &Path, known: bool, listed: String) -> Result<(), Failure> {
    if known {
        Ok(aureole_io::job::check_folder(path)?)
    } else {
        Err(aureole_io::Error::OutputFormat {
            path: path.to_path_buf(),
            extension: extension(path),
            allowed: listed,
        }
        .into())
    }
}
