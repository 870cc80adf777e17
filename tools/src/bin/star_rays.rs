//! Counts the diffraction rays around the brightest light of an HDR image:
//! the angular profile of luminance on rings around the light, each ring
//! divided by its own median (so the radial fall-off cancels and a ray is a
//! ratio above 1), averaged over the radii, and its peaks. For the gallery's
//! comparison of a real stop with ours (`scripts/gallery.sh`).
//!
//! ```sh
//! cargo run --release -p aureole-tools --bin star_rays -- IMAGE \
//!     [--radii R0,R1] [--exclude A0,A1] [--min-ratio X]
//! ```
//!
//! Angles are in degrees, counter-clockwise from the +x axis with y up;
//! `--exclude` leaves out a sector (what stands in front of the light).

#![deny(unsafe_code)]

use std::f64::consts::PI;
use std::path::PathBuf;
use std::process::ExitCode;

use aureole::Image;
use aureole_io::limits::Limits;
use aureole_io::read::read_image;

const STEPS: usize = 720;

struct Options {
    path: PathBuf,
    radii: (f64, f64),
    exclude: Vec<(f64, f64)>,
    min_ratio: f64,
}

fn main() -> ExitCode {
    match parse(std::env::args().skip(1)).and_then(|options| run(&options)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("star_rays: error: {message}");
            ExitCode::from(2)
        }
    }
}

fn pair(text: &str, name: &str) -> Result<(f64, f64), String> {
    let (a, b) = text
        .split_once(',')
        .ok_or(format!("{name} {text}: give two numbers, A,B"))?;
    let number = |t: &str| {
        t.trim()
            .parse::<f64>()
            .map_err(|_| format!("{name}: `{t}` is not a number"))
    };
    Ok((number(a)?, number(b)?))
}

fn parse(mut args: impl Iterator<Item = String>) -> Result<Options, String> {
    let usage = "usage: star_rays IMAGE [--radii R0,R1] [--exclude A0,A1] [--min-ratio X]";
    let mut options = Options {
        path: args.next().ok_or(usage)?.into(),
        radii: (20.0, 120.0),
        exclude: Vec::new(),
        min_ratio: 1.3,
    };
    while let Some(arg) = args.next() {
        let value = args.next().ok_or(format!("{arg} needs a value"))?;
        match arg.as_str() {
            "--radii" => options.radii = pair(&value, "--radii")?,
            "--exclude" => options.exclude.push(pair(&value, "--exclude")?),
            "--min-ratio" => {
                options.min_ratio = value
                    .parse()
                    .map_err(|_| format!("--min-ratio: `{value}` is not a number"))?
            }
            _ => return Err(format!("unknown option {arg}\n{usage}")),
        }
    }
    Ok(options)
}

/// The centroid of the pixels within 10 % of the peak luminance: the hottest
/// core of the light, where its rays start.
fn centre(luminance: &[f32], width: usize, peak: f32) -> (f64, f64) {
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
    for (i, &y) in luminance.iter().enumerate() {
        if y >= 0.9 * peak {
            sx += (i % width) as f64;
            sy += (i / width) as f64;
            n += 1.0;
        }
    }
    (sx / n, sy / n)
}

fn bilinear(luminance: &[f32], image: &Image, x: f64, y: f64) -> Option<f64> {
    if x < 0.0 || y < 0.0 || x >= (image.width - 1) as f64 || y >= (image.height - 1) as f64 {
        return None;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let at = |xx: usize, yy: usize| f64::from(luminance[yy * image.width + xx]);
    Some(
        (1.0 - fy) * ((1.0 - fx) * at(x0, y0) + fx * at(x0 + 1, y0))
            + fy * ((1.0 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1)),
    )
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn run(options: &Options) -> Result<(), String> {
    let image = read_image(&options.path, Limits::NONE)
        .map_err(|e| e.to_string())?
        .image;
    let luminance = image.luminance();
    let peak = luminance.iter().copied().fold(0.0f32, f32::max);
    let (cx, cy) = centre(&luminance, image.width, peak);
    let angle = |step: usize| step as f64 * 360.0 / STEPS as f64;
    let kept = |degrees: f64| {
        !options
            .exclude
            .iter()
            .any(|&(a, b)| degrees >= a && degrees <= b)
    };

    let mut profile = vec![0.0; STEPS];
    let mut rings = 0.0;
    let (r0, r1) = options.radii;
    let mut r = r0;
    while r <= r1 {
        let ring: Vec<Option<f64>> = (0..STEPS)
            .map(|step| {
                let theta = angle(step) * PI / 180.0;
                kept(angle(step))
                    .then(|| {
                        bilinear(
                            &luminance,
                            &image,
                            cx + r * theta.cos(),
                            cy - r * theta.sin(),
                        )
                    })
                    .flatten()
            })
            .collect();
        let mut present: Vec<f64> = ring.iter().flatten().copied().collect();
        if present.len() > STEPS / 4 {
            // Between the rays of a kernel the ring is black: there the
            // mean stands in for the median.
            let mean = present.iter().sum::<f64>() / present.len() as f64;
            let level = median(&mut present).max(0.01 * mean).max(f64::MIN_POSITIVE);
            for (sum, value) in profile.iter_mut().zip(&ring) {
                *sum += value.map_or(0.0, |v| v / level);
            }
            rings += 1.0;
        }
        r += 1.0;
    }
    if rings == 0.0 {
        return Err("no ring of those radii lies inside the image".into());
    }
    profile.iter_mut().for_each(|p| *p /= rings);

    // A ray is the highest point within ±10° and stands out of the rings.
    let window = STEPS / 36;
    let peaks: Vec<(f64, f64)> = (0..STEPS)
        .filter(|&i| {
            profile[i] >= options.min_ratio
                && (1..=window).all(|d| {
                    profile[i] >= profile[(i + d) % STEPS]
                        && profile[i] > profile[(i + STEPS - d) % STEPS]
                })
        })
        .map(|i| (angle(i), profile[i]))
        .collect();
    let core: Vec<f64> = luminance
        .iter()
        .filter(|&&y| y >= 0.01 * peak)
        .map(|&y| f64::from(y))
        .collect();
    println!(
        "light: {} px at 1 % of its peak or more, total luminance {:.1} (cd/m² × px)",
        core.len(),
        core.iter().sum::<f64>()
    );
    println!(
        "{}: light at ({cx:.1}, {cy:.1}), rings {r0}–{r1} px, {} ray(s) above {}× the ring median:",
        options.path.display(),
        peaks.len(),
        options.min_ratio
    );
    for (degrees, ratio) in &peaks {
        println!("  {degrees:6.1}°  {ratio:5.2}×");
    }
    let mut gaps: Vec<f64> = peaks.windows(2).map(|pair| pair[1].0 - pair[0].0).collect();
    if let (Some(first), Some(last)) = (peaks.first(), peaks.last()) {
        gaps.push(first.0 + 360.0 - last.0);
    }
    if !gaps.is_empty() {
        let gap_list: Vec<String> = gaps.iter().map(|g| format!("{g:.1}")).collect();
        println!("  gaps between neighbours: {}°", gap_list.join(", "));
    }
    Ok(())
}
