//! A picture file taken as a view to rate for glare ([`aureole::rating`]),
//! the same way from every front end: a Radiance picture in Radiance's
//! units (179 lm/W, its own primaries) with the view its header gives,
//! and the picture with its glare sources marked, as `evalglare -c`
//! writes one.

use aureole::rating::Rating;
use aureole::{Frame, FrameOptions, View};

use crate::display::{self, DisplayOptions, Exposure, Picture, ToneCurve};
use crate::formats::{Original, RADIANCE_PRIMARIES};
use crate::read::Loaded;

/// Radiance's luminous efficacy of its "white" light: a Radiance picture's
/// luminance is 179 lm/W times its Y, as every Radiance tool takes it.
pub const RADIANCE_EFFICACY: f64 = 179.0;

/// Where a rated picture's luminance scale came from, in words.
pub fn scale_words(loaded_radiance: bool, given: Option<f64>) -> Option<&'static str> {
    (loaded_radiance && given.is_none()).then_some("Radiance's 179 lm/W")
}

/// Prepares a file just read for rating: a Radiance picture without a
/// `PRIMARIES` line is in Radiance's primaries (its luminance 0.265 R +
/// 0.670 G + 0.065 B) and, unless `input_scale` says otherwise, holds
/// radiance at 179 lm/W. Returns how to make its frame.
pub fn frame_options(loaded: &mut Loaded, input_scale: Option<f64>) -> FrameOptions {
    let radiance = loaded.original.is_radiance();
    if radiance && loaded.image.primaries.is_none() {
        loaded.image.primaries = Some(RADIANCE_PRIMARIES);
    }
    FrameOptions {
        input_scale: input_scale.or(radiance.then_some(RADIANCE_EFFICACY)),
        sanitize: false,
    }
}

/// The view to rate `original`'s picture through: `given` (with where it
/// came from, in words), else its Radiance `VIEW=` header. `None` when
/// neither says.
pub fn view_of(
    original: &Original,
    given: Option<(View, &'static str)>,
) -> Option<aureole::Result<(View, &'static str)>> {
    if let Some((view, words)) = given {
        return Some(view.check().map(|()| (view, words)));
    }
    let header = original.radiance_view()?;
    Some(View::from_radiance(header).map(|v| (v, "the header's VIEW")))
}

/// Colours of the sources in the marked picture, in turn (evalglare's
/// order: red, green, blue, yellow, magenta, cyan).
const PALETTE: [[f32; 3]; 6] = [
    [1.0, 0.15, 0.1],
    [0.1, 0.9, 0.2],
    [0.2, 0.4, 1.0],
    [1.0, 0.85, 0.0],
    [0.9, 0.2, 0.9],
    [0.0, 0.9, 0.9],
];

/// The view tone-mapped (auto exposure, filmic), each glare source's
/// pixels tinted in its colour and its centre crossed.
pub fn marked(frame: &Frame, rating: &Rating) -> Picture {
    let options = DisplayOptions {
        exposure: Exposure::Auto,
        tone: ToneCurve::Filmic,
    };
    let mut picture = display::render(frame.image(), frame.scale(), &options);
    let (w, h) = (picture.width, picture.height);
    for (n, source) in rating.sources.iter().enumerate() {
        let colour = PALETTE[n % PALETTE.len()];
        for run in &source.runs {
            for column in run.start..run.end {
                let at = (run.row as usize * w + column as usize) * 3;
                for (v, c) in picture.rgb[at..at + 3].iter_mut().zip(colour) {
                    *v = 0.35 * *v + 0.65 * c;
                }
            }
        }
        let arm = (w.min(h) / 60).max(3) as i64;
        let (cx, cy) = (source.position[0] as i64, source.position[1] as i64);
        for d in -arm..=arm {
            for (x, y) in [(cx + d, cy), (cx, cy + d)] {
                if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                    let at = (y as usize * w + x as usize) * 3;
                    picture.rgb[at..at + 3].copy_from_slice(&colour);
                }
            }
        }
    }
    picture
}
