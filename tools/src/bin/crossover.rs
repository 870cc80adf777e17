//! Where splatting the kernel at bright pixels stops beating the FFT: a 4K
//! RGB frame of background 0.05 with N lights of 10³–10⁵ cd/m² (threshold
//! 100; N = 1350 is the issue-5 workload's image), the issue-5 PSF at
//! full-frame reach and capped at 401×401; median of 3 runs per method, and
//! what `Method::Auto` picks.
//!
//! `cargo run --release -p aureole-tools --bin crossover`

#![deny(unsafe_code)]

#[path = "../../../crates/aureole/benches/workload.rs"]
mod workload;

use std::time::Instant;

use aureole::{ApplyOptions, Image, Method, Plan};

fn median_ms(plan: &Plan, image: &Image, options: &ApplyOptions) -> f64 {
    let mut times: Vec<f64> = (0..3)
        .map(|_| {
            let start = Instant::now();
            let applied = plan.apply(image, 1.0, options, &mut |_| {});
            assert!(applied.is_ok());
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[1]
}

fn main() -> Result<(), aureole::Error> {
    let (w, h) = (3840, 2160);
    println!("| kernel | lights | FFT | splat | auto picks |");
    println!("|---|---|---|---|---|");
    for (name, cap) in [("401x401", Some((401, 401))), ("full frame", None)] {
        let plan = Plan::for_image(&workload::config(), w, h, cap)?;
        for n in [10usize, 40, 160, 640, 1350, 2560] {
            let image = if n == 1350 {
                workload::image(w, h)
            } else {
                workload::lights(w, h, n)
            };
            let options = |method| ApplyOptions {
                threshold: Some(100.0),
                method,
                ..ApplyOptions::default()
            };
            let fft = median_ms(&plan, &image, &options(Method::Fft));
            // Splatting a full-frame kernel at hundreds of lights takes
            // seconds and tells nothing new.
            let splat = if cap.is_none() && n > 200 {
                "-".to_string()
            } else {
                format!(
                    "{:.0} ms",
                    median_ms(&plan, &image, &options(Method::Splat))
                )
            };
            let auto = plan
                .apply(&image, 1.0, &options(Method::Auto), &mut |_| {})?
                .method;
            println!("| {name} | {n} | {fft:.0} ms | {splat} | {auto:?} |");
        }
    }
    Ok(())
}
