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
            if measured.picture.is_some() {
                continue;
            }
            let image = read_image(Path::new(&measured.file), limits)?.image;
            // A picture's luminance is its colour's weighted sum; a
            // grey one is a luminance PSF.
            let planes = match image.layout {
                Layout::Luminance => image.planes,
                Layout::Rgb if image.planes.windows(2).all(|p| p[0] == p[1]) => {
                    image.planes.into_iter().take(1).collect()
                }
                Layout::Rgb => image.planes,
            };
            measured.load(Picture {
                width: image.width,
                height: image.height,
                planes,
            });
        }
    }
    Ok(())
}
