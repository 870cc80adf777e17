//! `aureole apply`: what the camera would have recorded.

use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Instant;

use aureole::{Applied, ApplyOptions, Arithmetic, FrameOptions, Method, Session};
use aureole_io::compression::Compression;
use aureole_io::formats::{self, Samples};
use aureole_io::job::{Input, Job};
use aureole_io::kernel::read_kernel_file;
use aureole_io::limits::{default_memory_limit, Limits};
use aureole_io::spares::Spares;
use aureole_io::write::LinearOptions;
use clap::ArgMatches;

use crate::chain::ChainArgs;
use crate::device::DeviceArg;
use crate::display_args::DisplayArgs;
use crate::input::SourceArgs;
use crate::progress::Progress;
use crate::values::{parse_memory, parse_size};
use crate::{batch, input, output, Failure};

#[derive(clap::Args)]
#[command(after_help = format!(
    "The output's extension chooses what is written: {}. Linear files keep the input's own \
units (so the result composites back over the original); pictures for a display go through the \
exposure, the tone curve and sRGB. Without --preset or --config the default camera (preset {}) \
is used.",
    formats::image_outputs(),
    aureole::presets::DEFAULT_PRESET
))]
pub struct Args {
    #[arg(required = true, value_name = "INPUT", help = format!(
        "The HDR images: {}. Several may be given, or with --frames one pattern such as \
shot.%04d.exr",
        formats::readable()
    ))]
    inputs: Vec<PathBuf>,

    #[arg(short, long, value_name = "OUTPUT", help = format!(
        "Where to write the result: {}. With several inputs: a folder (each output takes its \
input's name) or, with --frames, a pattern such as out/shot.%04d.exr",
        formats::image_outputs()
    ))]
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
    /// it once, apply it to every frame. The camera's threshold comes with
    /// an EXR kernel (unless --threshold).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["preset", "config", "seed", "max_kernel"])]
    kernel: Option<PathBuf>,

    /// Apply a --kernel to frames of another width than the one it was
    /// built for (`psf --image-width`), which its µm and mm became pixels
    /// for: rays and halos then have the wrong size on the sensor. Needed
    /// too for a kernel that records no width (a .pfm).
    #[arg(long, requires = "kernel")]
    kernel_any_width: bool,

    /// Luminance threshold in cd/m²: pixels at or below it keep their light
    /// in place (overrides the config's `threshold`; 0 spreads every pixel).
    #[arg(long, value_name = "CD_PER_M2", allow_negative_numbers = true)]
    threshold: Option<f64>,

    /// Soft knee above the threshold, relative to it: the spread fraction
    /// rises smoothly from T to T·(1 + KNEE). 0 is the paper's hard threshold.
    #[arg(
        long,
        value_name = "KNEE",
        default_value = "0",
        allow_negative_numbers = true
    )]
    knee: f64,

    #[command(flatten)]
    source: SourceArgs,

    /// Replace NaN, infinite and negative samples by 0 (with a warning)
    /// instead of refusing the file (NaN, infinite) or passing them
    /// through (negative samples, with a note).
    #[arg(long)]
    sanitize: bool,

    /// Write only the light the camera adds (result − input), to add over
    /// the original in compositing.
    #[arg(long)]
    glare_only: bool,

    /// Also write, beside the result in the output EXR, the light each
    /// effect adds as a layer of its own (glare.bloom, glare.corona,
    /// glare.aperture, glare.halation, …; negative where it took light
    /// away) and the total (glare), which they sum to. Each effect after
    /// the first costs a kernel and a spread more.
    #[arg(long)]
    layers: bool,

    /// How to spread the bright pixels: auto picks by a cost estimate; fft
    /// costs the same however many are bright; splat adds the kernel at
    /// each one (fast for a few hundred lights or a small --max-kernel).
    #[arg(long, value_enum, default_value = "auto")]
    method: MethodArg,

    /// Store EXR output as half floats. Default: each channel as the input
    /// EXR stores it, else float32.
    #[arg(long, conflicts_with = "float")]
    half: bool,

    /// Store EXR output as float32 (see --half).
    #[arg(long)]
    float: bool,

    #[arg(long, value_name = "NAME", help = format!(
        "EXR output compression: {}. Default: the input's, when it is an EXR; else zip",
        Compression::names()
    ))]
    compression: Option<Compression>,

    /// Cap the kernel's extent in pixels (W or WxH); by default light from
    /// any pixel reaches the whole frame: (2W-1)x(2H-1).
    #[arg(long, value_name = "W[xH]", value_parser = parse_size)]
    max_kernel: Option<(usize, usize)>,

    /// Where the convolutions run: auto takes a hardware GPU (Vulkan,
    /// Metal, DX12) when there is one, and the CPU when there is none or
    /// the GPU cannot hold the kernel; gpu insists (a software adapter
    /// such as Mesa's lavapipe too); cpu never looks. The summary line
    /// says which ran.
    #[arg(long, value_enum, default_value_t = DeviceArg::Auto)]
    device: DeviceArg,

    #[command(flatten)]
    display: DisplayArgs,
}

impl Args {
    /// How the camera is applied: the threshold given, else the one the
    /// --kernel file records (`kernel_threshold`).
    fn options(&self, kernel_threshold: Option<f64>) -> ApplyOptions {
        ApplyOptions {
            threshold: self.threshold.or(kernel_threshold),
            knee: self.knee,
            glare_only: self.glare_only,
            method: match self.method {
                MethodArg::Auto => Method::Auto,
                MethodArg::Fft => Method::Fft,
                MethodArg::Splat => Method::Splat,
            },
        }
    }

    /// The one job of the input and output `pair`, as asked.
    fn job(&self, pair: batch::Pair) -> Job {
        let samples = match (self.half, self.float) {
            (true, _) => Some(Samples::Half),
            (_, true) => Some(Samples::Float),
            _ => None,
        };
        let linear = LinearOptions {
            samples,
            compression: self.compression,
        };
        Job {
            input: Some(pair.input),
            output: pair.output,
            choice: self.source.choice(),
            frame: FrameOptions {
                input_scale: self.source.input_scale,
                sanitize: self.sanitize,
            },
            options: self.options(None),
            layers: self.layers,
            write: output::options(linear, &self.display),
        }
    }
}

/// A Radiance picture's fisheye view (its `VIEW=` header: -vta, -vth or
/// -vts) for a chain of the eye alone whose `[camera]` gives no
/// projection: the eye is then spread over the sphere of the view's
/// directions.
fn header_view(
    config: &mut aureole::Config,
    path: &std::path::Path,
    quiet: bool,
) -> Result<(), Failure> {
    let eye_alone = matches!(config.effects.as_slice(), [aureole::Effect::Eye(_)]);
    if !eye_alone || config.camera.projection.is_some() {
        return Ok(());
    }
    let Some(text) = aureole_io::formats::read_radiance_view(path) else {
        return Ok(());
    };
    let view = aureole::View::from_radiance(&text)
        .map_err(|e| Failure::Usage(anyhow::anyhow!("{}: {e}", path.display())))?;
    if view.projection == aureole::Projection::Perspective {
        return Ok(());
    }
    config.camera.take_view(&view);
    if !quiet {
        say!(
            "aureole: note: {}: the header's VIEW ({view}) spreads the eye over the sphere of its directions",
            path.display()
        );
    }
    Ok(())
}

pub fn run(args: &Args, matches: &ArgMatches, quiet: bool) -> Result<(), Failure> {
    let pairs = batch::pairs(
        &args.inputs,
        &args.output,
        args.frames.as_ref().map(|f| f.0.as_slice()),
    )?;
    let mut jobs: Vec<Job> = pairs.into_iter().map(|pair| args.job(pair)).collect();
    for job in &jobs {
        // The probe file it makes is removed before an interruption exits.
        crate::interrupt::exclusive(|| job.check())?;
    }
    output::tidy(jobs.iter().map(|j| j.output.as_path()), quiet);
    let limit = args.max_memory.unwrap_or_else(default_memory_limit);
    let mut kernel_width = None;
    let mut kernel_threshold = None;
    let session = match &args.kernel {
        Some(path) => {
            let (kernel, record) = read_kernel_file(path, Limits { max_bytes: limit })?;
            if record.image_width.is_none() && !args.kernel_any_width {
                return Err(Failure::Usage(anyhow::anyhow!(
                    "{}: the kernel records no image width (a .pfm cannot; `aureole psf -o K.exr` records it), so whether its µm and mm became pixels at these frames' pitch cannot be checked; write it as .exr, or pass --kernel-any-width if it was built for frames this wide (psf --image-width)",
                    path.display()
                )));
            }
            kernel_width = record.image_width.filter(|_| !args.kernel_any_width);
            kernel_threshold = record.threshold;
            Session::with_kernel(kernel)
        }
        None => {
            let (mut config, defaulted) = args.chain.compose_or_default(matches, quiet)?;
            if let Some(job) = jobs.first() {
                header_view(&mut config, job.file(), quiet)?;
            }
            if defaulted && !quiet {
                say!(
                    "aureole: note: no --preset or --config: using the default camera, preset {}",
                    aureole::presets::DEFAULT_PRESET
                );
            }
            Session::new(config).with_max_extent(args.max_kernel)
        }
    };
    // The threshold of the camera a --kernel was built from, unless one
    // is given.
    let options = args.options(kernel_threshold);
    for job in &mut jobs {
        job.options = options;
    }
    let done = |job: &Job| args.skip_existing && job.output.is_file();
    let todo: Vec<&Job> = jobs.iter().filter(|job| !done(job)).collect();
    // In a batch the next frame is read and the last written meanwhile.
    let in_flight = if todo.len() > 1 { 2 } else { 0 };
    let session = session
        .with_memory_limit(limit)
        .with_device(args.device.into())
        .with_frames_in_flight(in_flight);
    // A frame too large for the memory or the kernel is refused from its
    // header, before it is decoded.
    if let Some(job) = todo.first() {
        job.check_header(&session, Limits { max_bytes: limit })
            .map_err(|e| input::failure(job.file(), e))?;
    }
    let skipped = jobs.len() - todo.len();
    if let [job] = jobs.as_slice() {
        if skipped == 1 {
            if !quiet {
                say!(
                    "aureole: note: {} exists: skipped (--skip-existing)",
                    job.output.display()
                );
            }
            return Ok(());
        }
    }
    let run = Run {
        args,
        kernel_width,
        limit,
        quiet,
        batch: jobs.len() > 1,
        // One frame keeps nothing: its buffers are freed as soon as done.
        spares: if jobs.len() > 1 {
            Spares::keeping()
        } else {
            Spares::default()
        },
        progress: Progress::new(quiet),
    };
    // The drivers load while the first frame is read.
    aureole::convolve::look_ahead(args.device.into());
    let failures = run.all(session, &todo);
    run.progress.finish();
    let failed = failures.len();
    if !run.batch {
        return failures.into_iter().next().map_or(Ok(()), Err);
    }
    let written = jobs.len() - failed - skipped;
    if !quiet || failed > 0 {
        say!(
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

/// What every frame of a batch is read and written with.
struct Run<'a> {
    args: &'a Args,
    /// The image width the --kernel was built for, to be held to.
    kernel_width: Option<usize>,
    limit: u64,
    quiet: bool,
    /// Several jobs: a frame's failure is said at once and the rest go on.
    batch: bool,
    /// The buffers of frames done, lent to the frames after them.
    spares: Spares,
    progress: Progress,
}

/// A frame read, waiting for the camera.
struct Read<'a> {
    job: &'a Job,
    input: Input,
    /// Seconds it took to read.
    reading: f64,
}

/// A frame through the camera, waiting to be written.
struct Convolved<'a> {
    read: Read<'a>,
    applied: Applied,
    kernel: (usize, usize),
    /// Seconds the camera took.
    convolving: f64,
}

impl Run<'_> {
    /// Every job, each frame read while the one before is convolved and
    /// written while the one after is: the reading and writing threads
    /// hold one frame each at most, handed over when the next is wanted
    /// (the session counts them in its memory estimate). Returns the
    /// failures, in order, each already said.
    fn all(&self, mut session: Session, jobs: &[&Job]) -> Vec<Failure> {
        let mut failures = Vec::new();
        std::thread::scope(|scope| {
            let (read_tx, reads) = mpsc::sync_channel::<Result<Read, Failure>>(0);
            let (write_tx, writes) = mpsc::sync_channel::<Convolved>(0);
            let (done_tx, done) = mpsc::channel::<Result<Vec<Vec<f32>>, Failure>>();
            scope.spawn(move || {
                for job in jobs {
                    if read_tx.send(self.read(job)).is_err() {
                        break;
                    }
                }
            });
            scope.spawn(move || {
                for result in writes {
                    if done_tx.send(self.write(result)).is_err() {
                        break;
                    }
                }
            });
            let finished = |outcome: Result<Vec<Vec<f32>>, Failure>,
                            session: &mut Session,
                            failures: &mut Vec<Failure>| match outcome {
                Ok(planes) => session.recycle_planes(planes),
                Err(failure) => self.failed(failure, failures),
            };
            for read in reads {
                while let Ok(outcome) = done.try_recv() {
                    finished(outcome, &mut session, &mut failures);
                }
                let applied = read.and_then(|read| self.apply(&mut session, read));
                match applied {
                    Ok(result) => {
                        if write_tx.send(result).is_err() {
                            break;
                        }
                    }
                    Err(failure) => self.failed(failure, &mut failures),
                }
            }
            drop(write_tx);
            for outcome in done {
                finished(outcome, &mut session, &mut failures);
            }
        });
        failures
    }

    /// A failed frame: said at once in a batch, kept for the summary.
    fn failed(&self, failure: Failure, failures: &mut Vec<Failure>) {
        if self.batch {
            let (Failure::Usage(e) | Failure::Run(e)) = &failure;
            self.progress
                .println(&format!("aureole: error: {}", crate::one_line(e)));
        }
        failures.push(failure);
    }

    fn read<'j>(&self, job: &'j Job) -> Result<Read<'j>, Failure> {
        let start = Instant::now();
        let limits = Limits {
            max_bytes: self.limit,
        };
        let input = input::read(job, limits, &self.spares, self.quiet)?;
        Ok(Read {
            job,
            input,
            reading: start.elapsed().as_secs_f64(),
        })
    }

    fn apply<'j>(
        &self,
        session: &mut Session,
        mut read: Read<'j>,
    ) -> Result<Convolved<'j>, Failure> {
        let args = self.args;
        let job = read.job;
        let width = read.input.frame.image().width;
        if let (Some(built), Some(kernel)) = (self.kernel_width, &args.kernel) {
            if built != width {
                return Err(Failure::Usage(anyhow::anyhow!(
                    "{}: the kernel {} was built for images {built} px wide (aureole psf --image-width), this one is {width} px wide: its µm and mm, which became pixels at that pitch, would be a factor {:.2} off here; build one with --image-width {width}, or pass --kernel-any-width",
                    job.file().display(),
                    kernel.display(),
                    built as f64 / width as f64
                )));
            }
        }
        if job.options.method == Method::Splat && !self.quiet {
            let costs = session
                .costs(&read.input.frame, &job.options)
                .map_err(|e| input::about(job.file(), e))?;
            if costs.splat > 60.0 {
                self.progress.println(&format!(
                    "aureole: warning: {}: splatting {} bright pixels will take about {} (the FFT about {:.1} s: --method auto or fft); Ctrl-C stops it",
                    job.file().display(),
                    costs.spread_pixels,
                    duration(costs.splat),
                    costs.fft
                ));
            }
        }
        let progress = &self.progress;
        let start = Instant::now();
        // A stereo plate's every view goes through the camera.
        let mut report = |stage, done| progress.update(stage, done);
        let applied = job
            .apply(&mut read.input, session, &mut report)
            .map_err(|e| input::about(job.file(), e))?;
        read.input.give_back_planes();
        let kernel = session
            .plan()
            .map_or((0, 0), |p| (p.kernel().width(), p.kernel().height()));
        Ok(Convolved {
            read,
            applied,
            kernel,
            convolving: start.elapsed().as_secs_f64(),
        })
    }

    /// Writes a result; hands its planes back for a later frame.
    fn write(&self, result: Convolved) -> Result<Vec<Vec<f32>>, Failure> {
        let Convolved {
            read,
            applied,
            kernel,
            convolving,
        } = result;
        let start = Instant::now();
        let job = read.job;
        let done = crate::interrupt::writing(|| job.write(read.input, applied))?;
        let shown = output::said(&job.output, &done.written, &self.progress);
        let (applied, image) = (&done.applied, &done.applied.image);
        if !self.quiet {
            let ratio = if applied.energy_in != 0.0 {
                format!("{:.4} %", 100.0 * applied.energy_out / applied.energy_in)
            } else {
                "-".to_string()
            };
            let spread = match (applied.method, applied.arithmetic) {
                (Method::Splat, _) => "splatted on the CPU".to_string(),
                (_, Arithmetic::Lamps(lamps)) => format!(
                    "FFT on {}, the near light of the {lamps} brightest px added exactly",
                    applied.device
                ),
                (_, Arithmetic::Double) => format!(
                    "FFT in f64 on {}: the scene's range is beyond f32",
                    applied.device
                ),
                (_, Arithmetic::Single) => format!("FFT on {}", applied.device),
            };
            // A chain of ghosts alone spreads nothing.
            let spread = if kernel == (0, 0) {
                "no kernel".to_string()
            } else {
                format!(
                    "kernel {}x{}, {} px above {} cd/m² ({spread})",
                    kernel.0, kernel.1, applied.spread_pixels, applied.threshold
                )
            };
            self.progress.println(&format!(
                "wrote {}: {}x{} {:?}, {spread}, energy in {:.6e} out {:.6e} ({ratio}){}; read {:.2} s, camera {:.2} s, write {:.2} s",
                job.output.display(),
                image.width,
                image.height,
                image.layout,
                applied.energy_in,
                applied.energy_out,
                shown.map(|s| format!(", {s}")).unwrap_or_default(),
                read.reading,
                convolving,
                start.elapsed().as_secs_f64()
            ));
            if let Some(ghosts) = &applied.ghosts {
                self.progress.println(&format!(
                    "  ghosts: {} of {} sources traced through {} paths at f/{:.2}, together {:.3e} of their light",
                    ghosts.traced, ghosts.found, ghosts.paths, ghosts.f_number, ghosts.light
                ));
            }
        }
        Ok(done.applied.image.planes)
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum MethodArg {
    Auto,
    Fft,
    Splat,
}

/// A long duration in words: minutes, or hours.
fn duration(seconds: f64) -> String {
    if seconds < 5400.0 {
        format!("{:.0} minutes", seconds / 60.0)
    } else {
        format!("{:.0} hours", seconds / 3600.0)
    }
}
