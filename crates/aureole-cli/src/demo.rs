//! `aureole demo`: a night street built in code, through the default camera.

use std::path::PathBuf;
use std::time::Instant;

use aureole::io::write::{write_linear, LinearOptions};
use aureole::{ApplyOptions, Plan};
use clap::ArgMatches;

use crate::chain::ChainArgs;
use crate::display_args::DisplayArgs;
use crate::progress::Progress;
use crate::{output, Failure};

#[derive(clap::Args)]
pub struct Args {
    /// Where to write the result: a picture (.png, .jpg, .tif) or linear (.exr, .hdr, .pfm).
    #[arg(short, long, value_name = "OUT.png")]
    output: PathBuf,

    /// Also write the linear input scene (cd/m²), to try your own settings on.
    #[arg(long, value_name = "OUT.exr")]
    hdr: Option<PathBuf>,

    /// Size of the scene in pixels.
    #[arg(long, value_name = "WxH", default_value = "1280x720", value_parser = crate::psf::parse_size)]
    size: (usize, usize),

    #[command(flatten)]
    chain: ChainArgs,

    #[command(flatten)]
    display: DisplayArgs,
}

pub fn run(args: &Args, matches: &ArgMatches, quiet: bool) -> Result<(), Failure> {
    output::check(&args.output, None)?;
    if let Some(hdr) = &args.hdr {
        output::check(hdr, None)?;
    }
    let (config, _) = args.chain.compose_or_default(matches)?;
    let start = Instant::now();
    let scene = aureole::demo::night_street(args.size.0, args.size.1);
    if let Some(hdr) = &args.hdr {
        crate::interrupt::writing(|| write_linear(hdr, &scene, LinearOptions::default()))?;
    }
    let progress = Progress::new(quiet);
    progress.stage("building kernel");
    let plan = Plan::new(&config, scene.width, scene.height, None)?;
    progress.stage("convolving");
    let options = ApplyOptions {
        threshold: config.threshold,
        ..ApplyOptions::default()
    };
    let applied = plan.apply(&scene, &options, &mut |f| progress.set(f))?;
    let shown = output::write(
        &args.output,
        &applied.image,
        1.0,
        &args.display,
        false,
        quiet,
    )?;
    progress.finish();
    if !quiet {
        eprintln!(
            "wrote {}: night street {}x{}, lamps of 2e4-1e5 cd/m², kernel {}x{}{}, {:.2} s",
            args.output.display(),
            scene.width,
            scene.height,
            plan.kernel().width(),
            plan.kernel().height(),
            shown.map(|s| format!(", {s}")).unwrap_or_default(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
