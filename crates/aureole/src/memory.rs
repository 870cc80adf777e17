//! How much memory a run will take, known before anything large is
//! allocated, and how much the machine can give.

use crate::config::Config;
use crate::convolve::plan::padded_size;
use crate::error::{Error, Result};
use crate::kernel::Extent;
use crate::psf::Effect;

/// The peak memory of applying a camera to one image, in bytes, and the
/// stage where it peaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Estimate {
    /// Bytes at the peak.
    pub bytes: u64,
    /// The stage that peaks, in words ("building the kernel", …).
    pub stage: &'static str,
}

/// What a run works on: the image and the kernel it will build (or load).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Workload {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Colour planes of the image (1 or 3), alpha not counted.
    pub channels: usize,
    /// Whether the image has an alpha plane.
    pub alpha: bool,
    /// Kernel extent in pixels.
    pub kernel: (usize, usize),
    /// Kernel channels (1, or 3 for a coloured kernel).
    pub kernel_channels: usize,
}

impl Workload {
    /// The workload of `config` on a `width`×`height` image of `channels`
    /// planes, with the kernel extent [`crate::Plan::new`] would choose.
    pub fn of_config(
        config: &Config,
        width: usize,
        height: usize,
        channels: usize,
        alpha: bool,
        max_extent: Option<(usize, usize)>,
    ) -> Result<Workload> {
        let extent = Extent::for_image_within(width, height, max_extent)?;
        Ok(Workload {
            width,
            height,
            channels,
            alpha,
            kernel: (extent.width, extent.height),
            kernel_channels: config
                .effects
                .iter()
                .map(Effect::channels)
                .max()
                .unwrap_or(1),
        })
    }

    /// The peak memory of building the kernel of `effects` (empty when the
    /// kernel is loaded from a file) and applying it to the image. The
    /// model counts the large buffers of each stage; measured peaks of
    /// whole runs (1080p and 4K, bloom, corona, diffraction, capped
    /// kernels) lie 0–25 % above it, so a quarter and the program's own
    /// baseline are added to stay on the safe side.
    pub fn estimate(&self, effects: &[Effect]) -> Estimate {
        const COMPLEX: u64 = 8;
        const BASELINE: u64 = 16 << 20;
        let pixels = self.width as u64 * self.height as u64;
        let planes = self.channels as u64 + u64::from(self.alpha);
        let image = pixels * planes * 4;
        let (kw, kh) = (self.kernel.0 as u64, self.kernel.1 as u64);
        let layer = kw * kh * 4;
        let kernel = layer * self.kernel_channels as u64;

        // Building: the chain so far and the next effect's layers; to
        // compose them, the zero-padded transform of one, the row spectra
        // of the other and the result; a diffraction pattern is held in f64
        // before it becomes f32.
        let (cx, cy) = padded_size(self.kernel.0, self.kernel.1, self.kernel.0, self.kernel.1);
        let compose = (cx as u64 / 2 + 1) * (cy as u64 + 2 * kh) * COMPLEX;
        let mut building = 0u64;
        let mut chain = 0u64;
        for (index, effect) in effects.iter().enumerate() {
            let layers = effect.channels() as u64;
            let pattern = match effect {
                Effect::Aperture(_) => 4 * layer * layers,
                _ => layer * layers + layer / 2,
            };
            let composing = if index > 0 {
                compose + layer * chain.max(layers)
            } else {
                0
            };
            building = building.max(layer * chain + pattern + composing);
            chain = chain.max(layers);
        }

        // Then the plan (the kernel and its spectrum at the apply size, and
        // the row spectra it keeps for every plane) and the output planes
        // stay until the result is written.
        let (px, py) = padded_size(self.kernel.0, self.kernel.1, self.width, self.height);
        let half = px as u64 / 2 + 1;
        let spectrum = half * py as u64 * COMPLEX * self.kernel_channels as u64;
        let rows = half * self.height as u64 * COMPLEX * self.channels as u64;
        let plan = kernel + spectrum + rows + image;
        let stages = [
            ("reading", 2 * image),
            ("building the kernel", building),
            (
                "transforming the kernel",
                kernel + spectrum + half * kh * COMPLEX,
            ),
            ("convolving", plan + image / 3),
            ("writing", plan + image + image / 2),
        ];
        let (stage, peak) = stages
            .into_iter()
            .max_by_key(|(_, bytes)| *bytes)
            .unwrap_or(("convolving", 0));
        // The input image stays in memory throughout.
        let bytes = image + peak;
        Estimate {
            bytes: bytes + bytes / 4 + BASELINE,
            stage,
        }
    }
}

/// The memory the system can give now (Linux: `MemAvailable` of
/// /proc/meminfo), if known.
pub fn available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The default memory limit: three quarters of what the system can give
/// now (leaving room for the rest of the machine), or 8 GiB where that is
/// unknown.
pub fn default_limit() -> u64 {
    available().map_or(8 << 30, |bytes| bytes / 4 * 3)
}

/// Parses a memory size: a number with an optional unit, K, M, G or T
/// (powers of 1024, with or without `iB`/`B`), e.g. `512M`, `1.5G`, `2GiB`.
pub fn parse_bytes(text: &str) -> Result<u64> {
    let refuse = |reason: &'static str| Error::Parameter {
        effect: "--max-memory".into(),
        name: "size",
        value: text.to_string(),
        allowed: reason,
    };
    let trimmed = text.trim();
    let split = trimmed
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(trimmed.len());
    let (number, unit) = trimmed.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| refuse("a number of bytes with an optional unit K, M, G or T, e.g. 4G"))?;
    let shift = match unit.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        _ => return Err(refuse("a unit among K, M, G, T (powers of 1024), e.g. 4G")),
    };
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(refuse("at least 1 byte, e.g. 512M or 4G"));
    }
    Ok(bytes as u64)
}

/// Bytes in binary units for people, e.g. `1.2 GiB`.
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit < UNITS.len() - 1 {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_binary_units() {
        assert_eq!(parse_bytes("512M").unwrap(), 512 << 20);
        assert_eq!(parse_bytes("1.5G").unwrap(), 3 << 29);
        assert_eq!(parse_bytes("2GiB").unwrap(), 2 << 30);
        assert_eq!(parse_bytes("1000").unwrap(), 1000);
        for bad in ["", "G", "-1G", "4X", "0"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
        assert_eq!(format_bytes(3 << 29), "1.5 GiB");
        assert_eq!(format_bytes(12), "12 B");
    }
}
