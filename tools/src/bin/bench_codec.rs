//! aureole's side of the codec table (bench/codec.py): one frame written and
//! read back through aureole-io, as `apply` writes and reads frames.
//!
//! `bench_codec FRAME.exr OUT_DIR [RUNS]` prints one JSON line per sample
//! type (half, float) and compression (zip, piz): the median seconds of
//! RUNS (default 5) writes and reads, the CPU seconds of one write, and the
//! file's size. It reads the file the peer wrote
//! (OUT_DIR/openexr-half-zip.exr …) where there is one, so that both read
//! the same bytes, else its own.
//!
//! `bench_codec kernel KERNEL.exr [RUNS]` prints the median seconds of
//! reading a kernel file as `apply --kernel` does (file, planes, checks and
//! normalisation).

#![deny(unsafe_code)]

use std::path::Path;
use std::time::Instant;

use aureole_io::compression::Compression;
use aureole_io::formats::Samples;
use aureole_io::limits::Limits;
use aureole_io::read::read_image;
use aureole_io::write::{write_linear, LinearOptions};

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// User and system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields 14 and 15 (utime, stime), counted after the command's ')'.
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or("", |(_, rest)| rest)
        .split_whitespace()
        .collect();
    let ticks: f64 = fields.get(11..13).map_or(0.0, |t| {
        t.iter().filter_map(|v| v.parse::<f64>().ok()).sum()
    });
    ticks / 100.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("kernel") {
        let path = Path::new(
            args.get(2)
                .ok_or("usage: bench_codec kernel KERNEL.exr [RUNS]")?,
        );
        let runs: usize = args.get(3).map_or(Ok(5), |r| r.parse())?;
        let mut reads = Vec::new();
        for _ in 0..runs {
            let start = Instant::now();
            let kernel = aureole_io::kernel::read_kernel_file(path, Limits::NONE)?;
            reads.push(start.elapsed().as_secs_f64());
            drop(kernel);
        }
        println!("{{\"kernel_read\": {:.4}}}", median(reads));
        return Ok(());
    }
    let (Some(frame), Some(out)) = (args.get(1), args.get(2)) else {
        return Err("usage: bench_codec FRAME.exr OUT_DIR [RUNS]".into());
    };
    let runs: usize = args.get(3).map_or(Ok(5), |r| r.parse())?;
    let image = read_image(Path::new(frame), Limits::NONE)?.image;
    std::fs::create_dir_all(out)?;
    for (samples, kind) in [(Samples::Half, "half"), (Samples::Float, "float")] {
        for compression in [Compression::Zip, Compression::Piz] {
            let path = Path::new(out).join(format!("aureole-{kind}-{compression}.exr"));
            let options = LinearOptions {
                samples: Some(samples),
                compression: Some(compression),
            };
            let mut writes = Vec::new();
            let mut cpu = Vec::new();
            for _ in 0..runs {
                let (start, cpu_start) = (Instant::now(), cpu_seconds());
                write_linear(&path, &image, options)?;
                writes.push(start.elapsed().as_secs_f64());
                cpu.push(cpu_seconds() - cpu_start);
            }
            let theirs = Path::new(out).join(format!("openexr-{kind}-{compression}.exr"));
            let read_from = if theirs.is_file() { &theirs } else { &path };
            let mut reads = Vec::new();
            for _ in 0..runs {
                let start = Instant::now();
                let loaded = read_image(read_from, Limits::NONE)?;
                reads.push(start.elapsed().as_secs_f64());
                drop(loaded);
            }
            println!(
                "{{\"tool\": \"aureole\", \"samples\": \"{kind}\", \"compression\": \"{compression}\", \"write\": {:.4}, \"write_cpu\": {:.3}, \"read\": {:.4}, \"bytes\": {}}}",
                median(writes),
                median(cpu),
                median(reads),
                std::fs::metadata(&path)?.len()
            );
        }
    }
    Ok(())
}
