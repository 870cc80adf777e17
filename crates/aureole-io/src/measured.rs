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
/// yet, within `limits`.
pub fn load(effects: &mut [Effect], limits: Limits) -> Result<()> {
    for effect in effects {
        if let Effect::Image(measured) = effect {
            if measured.picture.is_none() {
                measured.load(read_picture(Path::new(&measured.file), limits)?);
            }
        }
    }
    Ok(())
}

/// The PSF picture at `path`, within `limits`: one plane, or R, G and B
/// where they differ (a grey picture is a luminance PSF).
pub fn read_picture(path: &Path, limits: Limits) -> Result<Picture> {
    let image = read_image(path, limits)?.image;
    let planes = match image.layout {
        Layout::Rgb if image.planes.windows(2).all(|p| p[0] == p[1]) => {
            image.planes.into_iter().take(1).collect()
        }
        Layout::Luminance | Layout::Rgb => image.planes,
    };
    Ok(Picture {
        width: image.width,
        height: image.height,
        planes,
    })
}
