//! How soon a cancelled run stops: for each long loop of the library (a
//! rounded-blade lens kernel, a 4K corona kernel, the f32 FFT, splatting,
//! the f64 route), the time from raising the session's cancellation flag,
//! mid-run, to the call returning `Cancelled`. Five runs each; the median
//! and the largest.
//!
//! `cargo run --release -p aureole-tools --bin cancel_latency`

#![deny(unsafe_code)]

use std::thread;
use std::time::{Duration, Instant};

use aureole::{
    presets, ApplyOptions, Arithmetic, Cancel, Config, ConfigFile, Control, Error, Extent, Frame,
    FrameOptions, Method, Session,
};

const RUNS: usize = 5;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let lens = ConfigFile::load(std::path::Path::new("configs/night-street.toml"))
        .or_else(|_| presets::find("camera-f8-7blade")?.config())?;
    let mut rounded = Config::default();
    rounded.merge(lens);
    let corona = config("paper-fig6a")?;
    println!("| loop | cancelled after | latency median | latency max |");
    println!("|---|---|---|---|");

    let extent = Extent::for_image(1280, 720)?;
    report("rounded-blade lens kernel, 2559x1439", 1000, |cancel| {
        rounded
            .kernel_with(&extent, &mut Control::quiet(cancel))
            .map(drop)
    });
    let extent = Extent::for_image(3840, 2160)?;
    report("corona kernel, 7679x4319", 300, |cancel| {
        corona
            .kernel_with(&extent, &mut Control::quiet(cancel))
            .map(drop)
    });

    let street = aureole_io::demo::night_street(3840, 2160);
    for (preset, method, after) in [
        ("paper-fig4-bloom", Method::Fft, 100),
        ("camera-f8-7blade", Method::Fft, 300),
        ("paper-fig4-bloom", Method::Splat, 300),
    ] {
        let mut session = Session::new(config(preset)?);
        let frame = Frame::new(street.clone(), &FrameOptions::default())?;
        let options = ApplyOptions {
            method,
            ..ApplyOptions::default()
        };
        // The plan is built first (splatting a whole street would take
        // hours): what is measured is the apply alone.
        let build = ApplyOptions {
            method: Method::Fft,
            ..options
        };
        let built = session.apply(&frame, &build, &mut |_, _| {})?;
        let route = match (method, built.arithmetic) {
            (Method::Splat, _) => "splatting",
            (_, Arithmetic::Double) => "FFT in f64",
            (_, Arithmetic::Lamps(_)) => "FFT in f32, lamps apart",
            (_, Arithmetic::Single) => "FFT in f32",
        };
        let name = format!("{route}, 4K street, {preset}");
        report(&name, after, |cancel| {
            session.set_cancel_token(cancel.clone());
            session.apply(&frame, &options, &mut |_, _| {}).map(drop)
        });
    }
    Ok(())
}

fn config(preset: &str) -> Result<Config, aureole::Error> {
    let mut config = Config::default();
    config.merge(presets::find(preset)?.config()?);
    Ok(config)
}

/// Runs `work` RUNS times, cancelling it `after_ms` into each run, and
/// prints how long it took to return after the flag went up.
fn report(name: &str, after_ms: u64, mut work: impl FnMut(&Cancel) -> Result<(), Error>) {
    let mut latencies = Vec::new();
    for _ in 0..RUNS {
        let cancel = Cancel::new();
        let stopper = {
            let cancel = cancel.clone();
            thread::spawn(move || {
                thread::sleep(Duration::from_millis(after_ms));
                cancel.cancel();
                Instant::now()
            })
        };
        let result = work(&cancel);
        let returned = Instant::now();
        let Ok(raised) = stopper.join() else {
            continue;
        };
        match result {
            Err(Error::Cancelled) => {
                latencies.push(returned.saturating_duration_since(raised).as_secs_f64() * 1e3)
            }
            other => {
                println!("| {name} | {after_ms} ms | finished first ({other:?}) | |");
                return;
            }
        }
    }
    latencies.sort_by(f64::total_cmp);
    if let (Some(median), Some(max)) = (latencies.get(latencies.len() / 2), latencies.last()) {
        println!("| {name} | {after_ms} ms | {median:.1} ms | {max:.1} ms |");
    }
}
