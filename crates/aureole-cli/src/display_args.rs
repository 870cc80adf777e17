//! Display options: how a linear result becomes a picture.

use crate::values::parse_positive;
use aureole_io::display::{Depth, DisplayOptions, Exposure, ToneCurve};
use clap::builder::{PossibleValuesParser, TypedValueParser};

#[derive(clap::Args)]
pub struct DisplayArgs {
    /// Exposure of a picture: `auto` (a percentile meter: the lit scene's
    /// median at 12 % of white, unless more than 1 % of what is not a light
    /// source would clip; lamps may clip, as in a photograph) or EV at ISO
    /// 100, e.g. 10 for f/8 at 1/15 s (white = 1.2·2^EV cd/m²).
    #[arg(
        long,
        value_name = "EV|auto",
        default_value = "auto",
        allow_negative_numbers = true
    )]
    pub exposure: Exposure,

    /// The luminance in cd/m² shown as white (instead of --exposure).
    #[arg(long, value_name = "CD_PER_M2", conflicts_with = "exposure", value_parser = parse_positive)]
    pub white: Option<f64>,

    /// Tone curve from exposed light to the display: clip, reinhard or filmic.
    #[arg(long, value_name = "CURVE", default_value = "filmic",
          value_parser = PossibleValuesParser::new(ToneCurve::NAMES.map(|(name, _)| name))
              .try_map(|name| name.parse::<ToneCurve>()))]
    pub tonemap: ToneCurve,

    /// Bits per sample of a picture: 8 or 16 (PNG and TIFF; default 8 for
    /// PNG and JPEG, 16 for TIFF).
    #[arg(long, value_name = "8|16", value_parser = ["8", "16"])]
    pub bits: Option<String>,
}

impl DisplayArgs {
    pub fn options(&self) -> DisplayOptions {
        DisplayOptions {
            exposure: self.white.map_or(self.exposure, Exposure::White),
            tone: self.tonemap,
        }
    }

    /// The sample depth asked for; by default the format's own.
    pub fn depth(&self) -> Option<Depth> {
        match self.bits.as_deref() {
            Some("16") => Some(Depth::Sixteen),
            Some(_) => Some(Depth::Eight),
            None => None,
        }
    }
}
