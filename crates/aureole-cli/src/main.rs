//! `aureole`: the command-line shell over the aureole library.

#![deny(unsafe_code)]

/// `eprintln!` (or with `stdout:`, `println!`) that gives up quietly
/// where the stream is gone (a closed pipe, `2>&1 | head -1`): a message
/// nobody can read is no reason to fail the work, and `eprintln!` would
/// panic.
macro_rules! say {
    (stdout: $($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod allocator;
mod apply;
mod batch;
mod chain;
mod demo;
mod device;
mod display_args;
mod failure;
mod glare;
mod info;
mod input;
mod interrupt;
mod lens;
mod output;
mod presets;
mod progress;
mod psf;
mod studio;
mod values;
mod words;

pub use failure::Failure;

use std::process::ExitCode;

use clap::error::{ContextKind, ContextValue};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Physically based camera bloom, corona and glare for HDR images in cd/m².
#[derive(Parser)]
#[command(name = "aureole", version, about, long_about = None)]
struct Cli {
    /// Print nothing on stderr but errors.
    #[arg(long, short, global = true)]
    quiet: bool,

    /// Worker threads (default: RAYON_NUM_THREADS if set, else every core).
    /// The output is the same, byte for byte, for any count.
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: Option<u16>,

    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Apply the camera to an HDR image: write what it would have recorded.
    Apply(apply::Args),
    /// Render a built-in night street through the camera: aureole with nothing else.
    Demo(demo::Args),
    /// Rate a view's glare as evalglare does: E_v, DGP, DGI, UGR, VCP, CGI and the glare sources of a fisheye or perspective HDR picture.
    Glare(glare::Args),
    /// Describe an image: size, channels, luminance range, bright pixels.
    Info(info::Args),
    /// Describe a lens prescription (aureole's TOML, pbrt's .dat, lentil's JSON, an Optical Bench .txt): focal length, back focus, pupil, surfaces; -o writes it as TOML, --ghosts renders one source's ghosts.
    Lens(lens::Args),
    /// Write the camera's PSF as a convolution kernel (PFM, EXR or a PNG picture).
    Psf(psf::Args),
    /// List the built-in presets, or print one as TOML to start a config from.
    Presets(presets::Args),
    /// Tune the camera on an image in the browser: a local web studio.
    Studio(studio::Args),
}

fn main() -> ExitCode {
    let parsed = Cli::command()
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m).map(|cli| (m, cli)));
    let (matches, cli) = match parsed {
        Ok(parsed) => parsed,
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            // Clap's message is followed by a hint; one line is what the
            // user (and a log scanner) needs.
            let rendered = e.render().to_string();
            let mut line = rendered
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("")
                .to_string();
            // The hint lines say what is allowed: keep that on the line.
            if let Some(ContextValue::String(close)) = e.get(ContextKind::SuggestedValue) {
                line.push_str(&format!(" (did you mean '{close}'?)"));
            }
            if let Some(ContextValue::Strings(values)) = e.get(ContextKind::ValidValue) {
                line.push_str(&format!("; allowed: {}", values.join(", ")));
            }
            say!("aureole: {line}");
            return ExitCode::from(2);
        }
    };
    if !matches!(cli.command, Command::Studio(_)) {
        allocator::keep_freed_memory();
    }
    if let Some(threads) = cli.threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(usize::from(threads))
            .build_global();
        if let Err(e) = pool {
            say!("aureole: error: cannot start {threads} threads: {e}");
            return ExitCode::from(1);
        }
    }
    interrupt::install();
    let sub = |name| matches.subcommand_matches(name).unwrap_or(&matches);
    let result = match &cli.command {
        Command::Apply(args) => apply::run(args, sub("apply"), cli.quiet),
        Command::Demo(args) => demo::run(args, sub("demo"), cli.quiet),
        Command::Glare(args) => glare::run(args, cli.quiet),
        Command::Info(args) => info::run(args, cli.quiet),
        Command::Lens(args) => lens::run(args, cli.quiet),
        Command::Psf(args) => psf::run(args, sub("psf"), cli.quiet),
        Command::Presets(args) => presets::run(args),
        Command::Studio(args) => studio::run(args, cli.quiet),
    };
    aureole::convolve::looked_ahead();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(e)) => {
            say!("aureole: error: {}", one_line(&e));
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            say!("aureole: error: {}", one_line(&e));
            ExitCode::from(1)
        }
    }
}

/// An error and its context on one line, whatever a dependency put in its
/// message: a log scanner reads a failure per line.
pub fn one_line(error: &anyhow::Error) -> String {
    format!("{error:#}")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}
