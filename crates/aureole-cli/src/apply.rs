//! `aureole apply`: what the camera would have recorded.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::anyhow;
use aureole::io::read::{read_image_limited, Limits};
use aureole::memory::{format_bytes, Workload};
use aureole::{ApplyOptions, Config, Image, Kernel, Method, Plan};
use clap::ArgMatches;

use crate::chain::ChainArgs;
use crate::display_args::{parse_positive, DisplayArgs};
use crate::progress::Progress;
use crate::{batch, input, output, Failure};

#[derive(clap::Args)]
#[command(
    after_help = "The output's extension chooses what is written: .exr, .hdr and .pfm stay \
linear, in the input's own units (so the result composites back over the original); .png, .jpg \
and .tif are pictures for a display (exposure, tone curve, sRGB). Without --preset or --config \
the default camera (preset paper-fig5-both) is used."
)]
pub struct Args {
    /// The HDR images: OpenEXR, Radiance .hdr, PFM, or PNG, JPEG, TIFF.
    /// Several may be given, or with --frames one pattern such as
    /// shot.%04d.exr.
    #[arg(required = true, value_name = "INPUT")]
    inputs: Vec<PathBuf>,

    /// Where to write the result (.exr, .hdr, .pfm, .png, .jpg, .tif). With
    /// several inputs: a folder (each output takes its input's name) or,
    /// with --frames, a pattern such as out/shot.%04d.exr.
    #[arg(short, long, value_name = "OUTPUT")]
    output: PathBuf,

    /// The frame numbers that a %d (or %04d …) in the input stands for:
    /// 1-240, or a list such as 1-10,20,30-40.
    #[arg(long, value_name = "LIST", value_parser = batch::parse_frames)]
    frames: Option<batch::Frames>,

    /// Leave a frame whose output already exists (outputs are written whole
    /// or not at all, so an existing one is complete): an interrupted batch
    /// resumes where it stopped.
    #[arg(long)]
    skip_existing: bool,

    /// Stop before allocating when a frame would need more memory than this
    /// (e.g. 4G, 512M). Default: three quarters of the memory available
    /// when the run starts.
    #[arg(long, value_name = "SIZE", value_parser = parse_memory)]
    max_memory: Option<u64>,

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

    /// Replace NaN, infinite and negative samples by 0 (with a warning)
    /// instead of refusing the file.
    #[arg(long)]
    sanitize: bool,

    /// Keep negative samples as they are (they are never spread) instead of
    /// refusing the file.
    #[arg(long)]
    keep_negative: bool,

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

fn parse_memory(text: &str) -> Result<u64, String> {
    aureole::memory::parse_bytes(text).map_err(|e| e.to_string())
}

pub fn run(args: &Args, matches: &ArgMatches, quiet: bool) -> Result<(), Failure> {
    let jobs = batch::jobs(
        &args.inputs,
        &args.output,
        args.frames.as_ref().map(|f| f.0.as_slice()),
    )?;
    for job in &jobs {
        output::check(&job.output, Some(&job.input))?;
    }
    let (config, defaulted) = match &args.kernel {
        Some(_) => (Config::default(), false),
        None => args.chain.compose_or_default(matches)?,
    };
    if defaulted && !quiet {
        eprintln!(
            "aureole: note: no --preset or --config: using the default camera, preset {}",
            aureole::presets::DEFAULT_PRESET
        );
    }
    let limit = args
        .max_memory
        .unwrap_or_else(aureole::memory::default_limit);
    let mut session = Session {
        args,
        config,
        limit,
        quiet,
        plan: None,
        recycled: Vec::new(),
    };
    let done = |job: &batch::Job| args.skip_existing && job.output.is_file();
    if let [job] = jobs.as_slice() {
        if done(job) {
            if !quiet {
                eprintln!(
                    "aureole: note: {} exists: skipped (--skip-existing)",
                    job.output.display()
                );
            }
            return Ok(());
        }
        return session.frame(job);
    }
    let mut failed = 0;
    let mut skipped = 0;
    for job in &jobs {
        if done(job) {
            skipped += 1;
            continue;
        }
        if let Err(failure) = session.frame(job) {
            failed += 1;
            let (Failure::Usage(e) | Failure::Run(e)) = failure;
            eprintln!("aureole: error: {}", crate::one_line(&e));
        }
    }
    let written = jobs.len() - failed - skipped;
    if !quiet || failed > 0 {
        eprintln!(
            "aureole: {written} of {} frames written, {skipped} skipped (already there), {failed} failed",
            jobs.len()
        );
    }
    if failed > 0 {
        return Err(Failure::Run(anyhow::anyhow!(
            "{failed} of {} frames failed (see above); rerun with --skip-existing to do only those",
            jobs.len()
        )));
    }
    Ok(())
}

/// What stays from frame to frame: the plan (rebuilt only when the size
/// changes) and the previous result's planes.
struct Session<'a> {
    args: &'a Args,
    config: Config,
    limit: u64,
    quiet: bool,
    plan: Option<Plan>,
    recycled: Vec<Vec<f32>>,
}

impl Session<'_> {
    fn frame(&mut self, job: &batch::Job) -> Result<(), Failure> {
        let (args, quiet) = (self.args, self.quiet);
        let start = Instant::now();
        let options = input::Options {
            input_scale: args.input_scale,
            sanitize: args.sanitize,
            keep_negative: args.keep_negative,
            limits: Limits {
                max_bytes: self.limit,
            },
            quiet,
        };
        let input = input::read(&job.input, &options)?;
        let image = &input.loaded.image;
        if !quiet {
            eprintln!(
                "aureole: note: {}: luminance scale {} cd/m² per unit ({})",
                job.input.display(),
                input.scale,
                input.scale_source
            );
        }
        let progress = Progress::new(quiet);
        // A plan of another size goes before the new one is built.
        let reusable = self
            .plan
            .take()
            .filter(|p| p.size() == (image.width, image.height));
        let plan = match reusable {
            Some(plan) => self.plan.insert(plan),
            None => {
                self.recycled = Vec::new();
                progress.stage("building kernel");
                let built = self.build_plan(&job.input, image)?;
                self.plan.insert(built)
            }
        };
        progress.stage("convolving");
        let options = ApplyOptions {
            threshold: args.threshold.unwrap_or(self.config.threshold),
            knee: args.knee,
            scale: input.scale,
            glare_only: args.glare_only,
            method: match args.method {
                MethodArg::Auto => Method::Auto,
                MethodArg::Fft => Method::Fft,
                MethodArg::Splat => Method::Splat,
            },
        };
        let recycled = std::mem::take(&mut self.recycled);
        let applied = plan.apply_recycling(image, &options, recycled, &mut |f| progress.set(f))?;
        progress.stage("writing");
        let shown = output::write(
            &job.output,
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
                job.output.display(),
                image.width,
                image.height,
                image.layout,
                kernel.width(),
                kernel.height(),
                applied.spread_pixels,
                options.threshold,
                match (applied.method, applied.double) {
                    (Method::Splat, _) => "splatted",
                    (_, true) => "FFT in f64: the scene's range is beyond f32",
                    _ => "FFT",
                },
                applied.energy_in,
                applied.energy_out,
                shown.map(|s| format!(", {s}")).unwrap_or_default(),
                start.elapsed().as_secs_f64()
            );
        }
        self.recycled = applied.image.planes;
        Ok(())
    }

    /// The plan for `image`, once its memory is known to fit.
    fn build_plan(&self, path: &std::path::Path, image: &Image) -> Result<Plan, Failure> {
        let args = self.args;
        let channels = image.planes.len();
        let alpha = image.alpha.is_some();
        match &args.kernel {
            Some(kernel_path) => {
                let file = read_image_limited(
                    kernel_path,
                    Limits {
                        max_bytes: self.limit,
                    },
                )?
                .image;
                let workload = Workload {
                    width: image.width,
                    height: image.height,
                    channels,
                    alpha,
                    kernel: (file.width, file.height),
                    kernel_channels: file.planes.len(),
                };
                self.check_memory(path, &workload, &[], None)?;
                let kernel = Kernel::from_planes(file.width, file.height, file.planes)
                    .map_err(|e| Failure::Usage(anyhow!("{}: {e}", kernel_path.display())))?;
                Ok(Plan::from_kernel(kernel, image.width, image.height))
            }
            None => {
                let workload = Workload::of_config(
                    &self.config,
                    image.width,
                    image.height,
                    channels,
                    alpha,
                    args.max_kernel,
                )?;
                self.check_memory(path, &workload, &self.config.effects, args.max_kernel)?;
                Ok(Plan::new(
                    &self.config,
                    image.width,
                    image.height,
                    args.max_kernel,
                )?)
            }
        }
    }

    /// Refuses a run that would need more than the limit, saying how much it
    /// needs and what would fit.
    fn check_memory(
        &self,
        path: &std::path::Path,
        workload: &Workload,
        effects: &[aureole::Effect],
        max_kernel: Option<(usize, usize)>,
    ) -> Result<(), Failure> {
        let estimate = workload.estimate(effects);
        if estimate.bytes <= self.limit {
            return Ok(());
        }
        // The largest kernel extent, halving, that would fit.
        let (mut w, mut h) = max_kernel.unwrap_or(workload.kernel);
        let mut fits = None;
        while w > 16 && h > 16 {
            w /= 2;
            h /= 2;
            let smaller = Workload {
                kernel: (w.min(workload.kernel.0), h.min(workload.kernel.1)),
                ..*workload
            };
            let bytes = smaller.estimate(effects).bytes;
            if bytes <= self.limit {
                fits = Some((w, h, bytes));
                break;
            }
        }
        let hint = match (fits, effects.is_empty()) {
            (Some((w, h, bytes)), false) => format!(
                "--max-kernel {w}x{h} would need about {} (light then reaches {} px around a source)",
                format_bytes(bytes),
                w / 2
            ),
            (Some((w, h, _)), true) => {
                format!("a kernel of at most {w}x{h} (aureole psf --size {w}x{h}) would fit")
            }
            (None, _) => "the image alone is too large for it".to_string(),
        };
        Err(Failure::Run(anyhow!(
            "{}: needs about {} (peak while {}) but --max-memory is {}; {hint}, or raise --max-memory",
            path.display(),
            format_bytes(estimate.bytes),
            estimate.stage,
            format_bytes(self.limit)
        )))
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum MethodArg {
    Auto,
    Fft,
    Splat,
}
