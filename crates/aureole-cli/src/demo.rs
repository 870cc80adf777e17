//! `aureole demo`: a night street built in code, through the default camera.

use std::path::PathBuf;
use std::time::Instant;

use aureole::{ApplyOptions, Frame, FrameOptions, Session};
use aureole_io::limits::default_memory_limit;
use aureole_io::write::{write_image, write_linear, LinearOptions};
use clap::ArgMatches;

use crate::chain::ChainArgs;
use crate::display_args::DisplayArgs;
use crate::progress::Progress;
use crate::{output, Failure};

#[derive(clap::Args)]
pub struct Args {
    #[arg(short, long, value_name = "OUT.png", help = format!(
        "Where to write the result: {}",
        aureole_io::formats::image_outputs()
    ))]
    output: PathBuf,

    /// Also write the linear input scene (cd/m²), to try your own settings on.
    #[arg(long, value_name = "OUT.exr")]
    hdr: Option<PathBuf>,

    /// Size of the scene in pixels.
    #[arg(long, value_name = "WxH", default_value = "1280x720", value_parser = crate::values::parse_size)]
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
    let (config, _) = args.chain.compose_or_default(matches, quiet)?;
    let start = Instant::now();
    let scene = aureole_io::demo::night_street(args.size.0, args.size.1);
    if let Some(hdr) = &args.hdr {
        crate::interrupt::writing(|| write_linear(hdr, &scene, LinearOptions::default()))?;
    }
    let progress = Progress::new(quiet);
    let frame = Frame::new(scene, &FrameOptions::default())?;
    let mut session = Session::new(config).with_memory_limit(default_memory_limit());
    let applied = session
        .apply(&frame, &ApplyOptions::default(), &mut |stage, done| {
            progress.update(stage, done)
        })
        .map_err(|e| crate::input::about(std::path::Path::new("the demo scene"), e))?;
    let (width, height) = (frame.image().width, frame.image().height);
    let kernel = session
        .plan()
        .map_or((0, 0), |p| (p.kernel().width(), p.kernel().height()));
    let shown = output::write(
        &args.output,
        LinearOptions::default(),
        &args.display,
        &progress,
        |options| write_image(&args.output, &applied.image, 1.0, options),
    )?;
    progress.finish();
    if !quiet {
        say!(
            "wrote {}: night street {}x{}, lamps of 2e4-1e5 cd/m², kernel {}x{}{}, {:.2} s",
            args.output.display(),
            width,
            height,
            kernel.0,
            kernel.1,
            shown.map(|s| format!(", {s}")).unwrap_or_default(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
