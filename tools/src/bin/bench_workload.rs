//! Writes the issue-5 workload for the peer benchmark (bench/run.sh) and
//! times aureole's steady state on it.
//!
//! `cargo run --release -p aureole-tools --bin bench_workload -- 4k OUT_DIR` writes
//! OUT_DIR/image.npy (3×H×W f32), kernel.npy (Kh×Kw f32), result.npy (our
//! output) and aureole.json (median, min, max of 6 timed runs after one
//! warm-up, each frame reusing the previous frame's planes; the same with
//! fresh planes; kernel build time; peak memory in MB).

#![deny(unsafe_code)]

#[path = "../../../crates/aureole/benches/workload.rs"]
mod workload;

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use aureole::{ApplyOptions, Cancel, Control, Plan};

fn write_npy(path: &Path, shape: &[usize], data: impl Iterator<Item = f32>) -> std::io::Result<()> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let mut header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({},), }}",
        dims.join(", ")
    );
    // Magic (6) + version (2) + length (2) + header, padded with spaces to a
    // multiple of 64 and ended by a newline.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    out.write_all(b"\x93NUMPY\x01\x00")?;
    out.write_all(&(header.len() as u16).to_le_bytes())?;
    out.write_all(header.as_bytes())?;
    for v in data {
        out.write_all(&v.to_le_bytes())?;
    }
    out.flush()
}

fn peak_memory_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .map(str::to_owned)
        })
        .and_then(|l| {
            l.split_whitespace()
                .nth(1)
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (w, h) = match args.get(1).map(String::as_str) {
        Some("1080p") => (1920, 1080),
        Some("4k") => (3840, 2160),
        _ => return Err("usage: bench_workload 1080p|4k OUT_DIR".into()),
    };
    let dir = Path::new(
        args.get(2)
            .ok_or("usage: bench_workload 1080p|4k OUT_DIR")?,
    );
    std::fs::create_dir_all(dir)?;
    let image = workload::image(w, h);
    let start = Instant::now();
    let plan = Plan::for_image(&workload::config(), w, h, None)?;
    let kernel_build = start.elapsed().as_secs_f64();
    let options = ApplyOptions::default();
    // Fresh output planes every run, as a single call makes them.
    plan.apply(&image, 1.0, &options, &mut |_| {})?;
    let mut fresh = Vec::new();
    for _ in 0..6 {
        let start = Instant::now();
        plan.apply(&image, 1.0, &options, &mut |_| {})?;
        fresh.push(start.elapsed().as_secs_f64());
    }
    fresh.sort_by(f64::total_cmp);
    // A frame sequence: each frame reuses the previous frame's planes.
    let mut times = Vec::new();
    let cancel = Cancel::new();
    let mut result = plan.apply(&image, 1.0, &options, &mut |_| {})?;
    for _ in 0..6 {
        let start = Instant::now();
        let mut control = Control::quiet(&cancel);
        result = plan.apply_with(&image, 1.0, &options, result.image.planes, &mut control)?;
        times.push(start.elapsed().as_secs_f64());
    }
    let memory = peak_memory_mb();
    times.sort_by(f64::total_cmp);
    let median = (times[2] + times[3]) / 2.0;
    let fresh_median = (fresh[2] + fresh[3]) / 2.0;
    let result = result.image;
    write_npy(
        &dir.join("image.npy"),
        &[3, h, w],
        image.planes.iter().flatten().copied(),
    )?;
    let kernel = plan.kernel();
    write_npy(
        &dir.join("kernel.npy"),
        &[kernel.height(), kernel.width()],
        kernel.planes()[0].iter().copied(),
    )?;
    write_npy(
        &dir.join("result.npy"),
        &[3, h, w],
        result.planes.iter().flatten().copied(),
    )?;
    std::fs::write(
        dir.join("aureole.json"),
        format!(
            "{{\"median\": {median}, \"min\": {}, \"max\": {}, \"fresh_median\": {fresh_median}, \"fresh_min\": {}, \"fresh_max\": {}, \"kernel_build\": {kernel_build}, \"peak_mb\": {memory}}}\n",
            times[0],
            times[5],
            fresh[0],
            fresh[5]
        ),
    )?;
    println!(
        "aureole {w}x{h}: median {:.1} ms, kernel build {:.2} s",
        median * 1e3,
        kernel_build
    );
    Ok(())
}
