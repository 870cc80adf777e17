//! The pictures of measured PSFs (`type = "image"` effects): the library
//! reads no files, so the front ends read each one here and hand its
//! planes to the effect.

use std::path::Path;

use aureole::optics::measured::Picture;
use aureole::{ConfigFile, Effect, Layout};

use crate::error::Result;
use crate::limits::Limits;
use crate::read::read_image;

/// Makes the relative `file` of each measured PSF in `file` relative to
/// `folder`, the folder of the config file that names it.
pub fn resolve(file: &mut ConfigFile, folder: &Path) {
    for effect in &mut file.effects {
        if let Effect::Image(measured) = effect {
            let path = Path::new(&measured.file);
            if path.is_relative() {
                measured.file = folder.join(path).to_string_lossy().into_owned();
            }
        }
    }
}

/// Reads the picture of every measured PSF among `effects` that has none
/// yet, within `limits`; returns a warning, a line each, for each picture
/// that cannot hold its PSF whole ([`read_picture`]).
pub fn load(effects: &mut [Effect], limits: Limits) -> Result<Vec<String>> {
    let mut warnings = Vec::new();
    for effect in effects {
        if let Effect::Image(measured) = effect {
            if measured.picture.is_none() {
                let (picture, said) = read_picture(Path::new(&measured.file), limits)?;
                measured.load(picture);
                warnings.extend(said);
            }
        }
    }
    Ok(warnings)
}

/// The PSF picture at `path`, within `limits`: one plane, or R, G and B
/// where they differ (a grey picture is a luminance PSF). With it, a
/// warning where a display picture (8 or 16 bits) has samples at its
/// ceiling: a star's core brighter than the picture holds is cut there,
/// which leaves the kernel's core too weak against its rays.
pub fn read_picture(path: &Path, limits: Limits) -> Result<(Picture, Option<String>)> {
    let loaded = read_image(path, limits)?;
    let image = loaded.image;
    let clipped = if loaded.display_referred {
        clipped_pixels(&image.planes)
    } else {
        0
    };
    let warning = (clipped > 1).then(|| {
        format!(
            "{}: {clipped} px are at the picture's ceiling (its largest code value): the star's core is clipped, so its kernel's core is too weak against its rays; use a float picture (EXR, Radiance HDR or PFM) or one merged from a bracket of exposures",
            path.display()
        )
    });
    let planes = match image.layout {
        Layout::Rgb if image.planes.windows(2).all(|p| p[0] == p[1]) => {
            image.planes.into_iter().take(1).collect()
        }
        Layout::Luminance | Layout::Rgb => image.planes,
    };
    Ok((
        Picture {
            width: image.width,
            height: image.height,
            planes,
        },
        warning,
    ))
}

/// The pixels of a display picture (decoded to 0…1) with a sample at the
/// largest code value, 1.
fn clipped_pixels(planes: &[Vec<f32>]) -> usize {
    let pixels = planes.first().map_or(0, Vec::len);
    (0..pixels)
        .filter(|&i| planes.iter().any(|p| p[i] >= 1.0))
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write::{write_image, LinearOptions, WriteOptions};
    use aureole::Image;

    /// A star: a core of `peak` and a few rays, as a camera records it.
    fn star(peak: f32) -> Image {
        let mut image = Image::filled(41, 41, Layout::Luminance, 0.0);
        for (i, v) in image.planes[0].iter_mut().enumerate() {
            let (x, y) = ((i % 41) as f32 - 20.0, (i / 41) as f32 - 20.0);
            let r = (x * x + y * y).sqrt();
            *v = peak / (1.0 + r * r) + if x == 0.0 || y == 0.0 { 0.02 } else { 0.0 };
        }
        image
    }

    #[test]
    fn a_display_picture_with_a_clipped_core_is_warned_about_and_a_float_one_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let limits = Limits::default_for_machine();
        let png = dir.path().join("star.png");
        // Exposed so that the core's 3x3 and more reach the ceiling.
        let options = WriteOptions {
            linear: LinearOptions::default(),
            display: crate::display::DisplayOptions {
                exposure: crate::display::Exposure::White(1.0),
                tone: crate::display::ToneCurve::Clip,
            },
            depth: None,
        };
        write_image(&png, &star(8.0), 1.0, &options).unwrap();
        let (_, warning) = read_picture(&png, limits).unwrap();
        let warning = warning.expect("a warning");
        assert!(
            warning.starts_with(&format!("{}: ", png.display())),
            "{warning}"
        );
        assert!(
            warning.contains("px are at the picture's ceiling"),
            "{warning}"
        );
        // Unclipped, or in float, nothing to say.
        write_image(&png, &star(0.5), 1.0, &options).unwrap();
        assert_eq!(read_picture(&png, limits).unwrap().1, None);
        let pfm = dir.path().join("star.pfm");
        write_image(&pfm, &star(8.0), 1.0, &options).unwrap();
        assert_eq!(read_picture(&pfm, limits).unwrap().1, None);
    }
}
