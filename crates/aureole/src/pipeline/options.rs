//! What a caller asks of one application of the camera, and what it gets
//! back.

use crate::image::Image;

/// How the light is split and what is written.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ApplyOptions {
    /// Threshold T in cd/m²: pixels whose luminance is at or below it keep
    /// their light in place. `None`: the configuration's `threshold` (0 for
    /// a kernel given ready-made).
    pub threshold: Option<f64>,
    /// Soft knee, relative to T: between T and T·(1 + knee) the spread
    /// fraction rises smoothly from 0 to 1. 0 is the paper's hard threshold.
    pub knee: f64,
    /// Write only the light the camera adds (output − input), for
    /// compositing additively over the original.
    pub glare_only: bool,
    /// How the bright pixels are spread.
    pub method: Method,
}

impl ApplyOptions {
    /// Refuses a threshold or knee no front end accepts: the threshold a
    /// finite luminance of at least 0 (a negative one would spread every
    /// pixel, NaN none), the knee a finite number of at least 0. Every
    /// application checks this, so the command line, the studio and Python
    /// refuse the same values in the same words.
    pub fn check(&self) -> crate::Result<()> {
        let refuse = |name, value: f64, allowed| crate::Error::Parameter {
            effect: "apply".into(),
            name,
            value: value.to_string(),
            allowed,
        };
        if let Some(t) = self.threshold.filter(|t| !(t.is_finite() && *t >= 0.0)) {
            return Err(refuse(
                "threshold",
                t,
                "a finite luminance of at least 0 cd/m² (0 spreads every pixel)",
            ));
        }
        if !(self.knee.is_finite() && self.knee >= 0.0) {
            return Err(refuse(
                "knee",
                self.knee,
                "a finite number of at least 0 (0 is the hard threshold)",
            ));
        }
        Ok(())
    }
}

/// How the light of the bright pixels is spread. Both give the same result
/// up to f32 round-off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Whichever the cost estimate says is faster for this image.
    #[default]
    Auto,
    /// The FFT convolution of the bright planes: its cost does not depend
    /// on how many pixels are bright.
    Fft,
    /// The kernel added, weighted, at every bright pixel: cheaper for a few
    /// bright pixels or a small kernel, and exact in f32.
    Splat,
}

impl std::str::FromStr for Method {
    type Err = crate::Error;

    /// `auto`, `fft` or `splat`, as every front end names them.
    fn from_str(name: &str) -> crate::Result<Method> {
        match name {
            "auto" => Ok(Method::Auto),
            "fft" => Ok(Method::Fft),
            "splat" => Ok(Method::Splat),
            other => Err(crate::Error::Parameter {
                effect: "apply".into(),
                name: "method",
                value: format!("{other:?}"),
                allowed: "auto, fft or splat",
            }),
        }
    }
}

/// The result of applying a plan.
#[derive(Debug, Clone)]
pub struct Applied {
    /// The camera's image (or only its glare), in the input's units.
    pub image: Image,
    /// Σ luminance of the input, file units.
    pub energy_in: f64,
    /// Σ luminance of the camera's image, file units: the input's less what
    /// was spread beyond the frame.
    pub energy_out: f64,
    /// How many pixels were above the threshold and spread.
    pub spread_pixels: usize,
    /// The threshold applied, cd/m².
    pub threshold: f64,
    /// How they were spread ([`Method::Fft`] or [`Method::Splat`]).
    pub method: Method,
    /// The arithmetic of the FFT, chosen from the scene's range.
    pub arithmetic: Arithmetic,
    /// Where the light was spread, in words (the GPU's name, or the CPU
    /// and why).
    pub device: String,
    /// The lens ghosts, when the config traces them.
    pub ghosts: Option<super::GhostSummary>,
}

/// `planes` less `input`'s, plane by plane: a result's glare alone
/// ([`ApplyOptions::glare_only`]).
pub(crate) fn subtract_input(planes: &mut [Vec<f32>], input: &[Vec<f32>]) {
    use rayon::prelude::*;
    for (out, input) in planes.iter_mut().zip(input) {
        out.par_iter_mut().zip(input).for_each(|(o, i)| *o -= i);
    }
}

impl Applied {
    /// `image` as it is: a chain that spreads nothing (ghosts alone).
    pub(crate) fn unspread(image: Image, threshold: f64) -> Applied {
        let energy = image.total_luminance();
        Applied {
            image,
            energy_in: energy,
            energy_out: energy,
            spread_pixels: 0,
            threshold,
            method: Method::Fft,
            arithmetic: Arithmetic::Single,
            device: "the CPU".to_string(),
            ghosts: None,
        }
    }
}

/// The arithmetic an application used (docs/physics.md §8): f32 unless its
/// round-off would show in the dark pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Arithmetic {
    /// f32 throughout (or no FFT at all).
    #[default]
    Single,
    /// f32, with the light near the brightest pixels (this many) added
    /// exactly, so that their round-off stays below the dark pixels.
    Lamps(usize),
    /// f64: the scene's range is beyond f32 even with its lamps apart.
    Double,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_and_knees_outside_their_range_are_refused_naming_them() {
        let fine = ApplyOptions {
            threshold: Some(0.0),
            knee: 0.5,
            ..ApplyOptions::default()
        };
        assert!(fine.check().is_ok());
        assert!(ApplyOptions::default().check().is_ok());
        for threshold in [-1.0, f64::NAN, f64::INFINITY] {
            let refused = ApplyOptions {
                threshold: Some(threshold),
                ..fine
            }
            .check()
            .unwrap_err()
            .to_string();
            assert!(refused.starts_with("apply: threshold = "), "{refused}");
            assert!(refused.contains("at least 0 cd/m²"), "{refused}");
        }
        for knee in [-0.1, f64::NAN, f64::NEG_INFINITY] {
            let refused = ApplyOptions { knee, ..fine }
                .check()
                .unwrap_err()
                .to_string();
            assert!(refused.starts_with("apply: knee = "), "{refused}");
        }
    }

    #[test]
    fn methods_are_read_by_their_names_and_others_refused_listing_them() {
        assert_eq!("auto".parse::<Method>().unwrap(), Method::Auto);
        assert_eq!("fft".parse::<Method>().unwrap(), Method::Fft);
        assert_eq!("splat".parse::<Method>().unwrap(), Method::Splat);
        let refused = "magic".parse::<Method>().unwrap_err().to_string();
        assert_eq!(
            refused,
            "apply: method = \"magic\" is not allowed: auto, fft or splat"
        );
    }
}
