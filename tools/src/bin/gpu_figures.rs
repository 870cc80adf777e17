//! The GPU engine's figures (issue 30) beside the CPU's, in one run on one
//! machine: for the issue-5 workload and the demo night street
//! (`camera-f8-7blade`, its lamps apart), the latter also in half floats
//! as a half EXR decodes (its planes go up to a GPU as halves), at each
//! size, the plan's build
//! (kernel and spectra), the steady-state frame from planes in memory to
//! result planes (upload and download included; median, min and max of
//! `RUNS` after one warm-up) and the GPU result against the CPU's
//! (relative L2, worst pixel).
//!
//! `cargo run --release -p aureole-tools --bin gpu_figures -- 1080p 4k`
//! (`RUNS=7` by default). Without a GPU it says so and times the CPU.

#![deny(unsafe_code)]

#[path = "../../../crates/aureole/benches/workload.rs"]
mod workload;

use std::time::Instant;

use aureole::{presets, ApplyOptions, Config, Device, Image, Plan};

fn main() {
    let sizes: Vec<String> = std::env::args().skip(1).collect();
    let runs: usize = std::env::var("RUNS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(7);
    match aureole::convolve::choose(Device::Gpu) {
        Ok((_, words)) => println!("device: {words}"),
        Err(why) => println!("device: none ({why})"),
    }
    for size in if sizes.is_empty() {
        vec!["1080p".to_string()]
    } else {
        sizes
    } {
        let (w, h) = match size.as_str() {
            "4k" => (3840, 2160),
            "720p" => (1280, 720),
            _ => (1920, 1080),
        };
        let mut lens = Config::default();
        lens.merge(
            presets::find("camera-f8-7blade")
                .and_then(|p| p.config())
                .expect("preset"),
        );
        let street = aureole_io::demo::night_street(w, h);
        let scenes = [
            (
                "issue-5 workload",
                workload::config(),
                workload::image(w, h),
            ),
            ("night street", lens.clone(), street.clone()),
            ("night street in halves", lens, in_halves(street)),
        ];
        for (name, config, image) in scenes {
            let kernel = Plan::for_image(&config, w, h, None)
                .expect("plan")
                .into_kernel();
            let mut results: Vec<Image> = Vec::new();
            for device in [Device::Cpu, Device::Gpu] {
                let start = Instant::now();
                let plan = match Plan::with_kernel_on(kernel.clone(), (w, h), device) {
                    Ok(plan) => plan,
                    Err(why) => {
                        println!("{size} {name} on {}: {why}", device.name());
                        continue;
                    }
                };
                let options = ApplyOptions::default();
                let first = plan
                    .apply(&image, 1.0, &options, &mut |_| {})
                    .expect("apply");
                let build = start.elapsed().as_secs_f64();
                let mut times = Vec::with_capacity(runs);
                let mut planes = first.image.planes.clone();
                for _ in 0..runs {
                    let start = Instant::now();
                    let applied = plan
                        .apply_with(
                            &image,
                            1.0,
                            &options,
                            std::mem::take(&mut planes),
                            &mut aureole::Control::quiet(&aureole::Cancel::new()),
                        )
                        .expect("apply");
                    times.push(start.elapsed().as_secs_f64() * 1e3);
                    planes = applied.image.planes;
                }
                times.sort_by(f64::total_cmp);
                println!(
                    "{size} {name} on {} ({:?}): first frame with the plan {build:.2} s; frame median {:.1} ms (min {:.1}, max {:.1}, {runs} runs)",
                    plan.device(),
                    first.arithmetic,
                    times[times.len() / 2],
                    times[0],
                    times[times.len() - 1],
                );
                results.push(first.image);
            }
            if let [cpu, gpu] = results.as_slice() {
                let (mut diff, mut norm, mut worst) = (0.0f64, 0.0f64, 0.0f64);
                for (g, c) in gpu.planes.iter().zip(&cpu.planes) {
                    for (a, b) in g.iter().zip(c) {
                        let d = f64::from(*a) - f64::from(*b);
                        diff += d * d;
                        norm += f64::from(*b).powi(2);
                        if *b != 0.0 {
                            worst = worst.max((d / f64::from(*b)).abs());
                        }
                    }
                }
                println!(
                    "{size} {name}: GPU against CPU, relative L2 {:.2e}, worst pixel {worst:.2e}",
                    (diff / norm).sqrt()
                );
            }
        }
    }
}

/// `image` as a half-float EXR holds it: in units of 16 cd/m², so that
/// its 10⁵ cd/m² lamps stay below the halves' 65504, every value rounded
/// to a half.
fn in_halves(mut image: Image) -> Image {
    for plane in &mut image.planes {
        for v in plane.iter_mut() {
            *v = half::f16::from_f32(*v / 16.0).to_f32();
        }
    }
    image
}
