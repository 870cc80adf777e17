//! Glare in its own layers: the light each effect of the chain adds, for a
//! compositor to keep beside the beauty and grade apart.
//!
//! Effects compose by convolution, so one effect's glare depends on those
//! before it. Layer i is what the chain up to effect i gives less what the
//! chain before it gives, O₁..ᵢ − O₁..ᵢ₋₁ (O₀ the input): the layers sum,
//! telescoping, to the total glare O − I, and each holds the light its
//! effect moved, negative where it took light away (the lamps' cores).
//! Lens ghosts, traced before the chain, come first: `glare.ghosts` is the
//! scene with its ghosts less the input, and the chain's layers spread
//! that scene.

use rayon::prelude::*;

use super::options::{Applied, ApplyOptions};
use super::session::{Frame, Session, Stage};
use crate::error::Result;
use crate::image::Image;

/// One layer of glare: its name (`glare.bloom`, `glare` for the total) and
/// its planes, in the input's units and layout, without alpha.
#[derive(Debug, Clone)]
pub struct GlareLayer {
    /// The layer's name, as an EXR channel prefix: `glare.<type>` for an
    /// effect (a second of the same type `glare.<type>2`), `glare` for
    /// the total.
    pub name: String,
    /// The light it adds (negative where it takes light away).
    pub image: Image,
}

/// The name of each effect's layer: `glare.<type>`, numbered from the
/// second of a type on.
fn names<'a>(kinds: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut seen: Vec<&str> = Vec::new();
    kinds
        .map(|kind| {
            seen.push(kind);
            match seen.iter().filter(|k| **k == kind).count() {
                1 => format!("glare.{kind}"),
                n => format!("glare.{kind}{n}"),
            }
        })
        .collect()
}

/// `after − before`, plane by plane, without alpha.
fn difference(after: &Image, before: &Image) -> Image {
    let mut image = after.clone_without_planes();
    image.alpha = None;
    image.planes = after
        .planes
        .iter()
        .zip(&before.planes)
        .map(|(a, b)| a.par_iter().zip(b).map(|(a, b)| a - b).collect())
        .collect();
    image
}

impl Session {
    /// [`Session::apply`], with the light each effect adds in a layer of
    /// its own and the total glare last; a kernel given ready-made has the
    /// total alone. Each effect but the last costs a spread more, and a
    /// kernel more (the chain up to it) for the first frame of a size; the
    /// chains' plans are kept for the next frame where the memory limit
    /// holds them all, else built again.
    pub fn apply_layers(
        &mut self,
        frame: &Frame,
        options: &ApplyOptions,
        progress: &mut dyn FnMut(Stage, f64),
    ) -> Result<(Applied, Vec<GlareLayer>)> {
        let whole = ApplyOptions {
            glare_only: false,
            ..*options
        };
        let kinds: Vec<&'static str> = self
            .config()
            .map(|c| c.effects.iter().map(|e| e.kind()).collect())
            .unwrap_or_default();
        let names = names(kinds.into_iter());
        let before_last = names.len().saturating_sub(1);
        // The chains before the last effect, kept from the last frame (their
        // plans reused when the size is the same) or made: the frames held
        // beside each run are the input, the chain before and the layers
        // so far.
        let mut chain = std::mem::take(&mut self.layer_chain);
        if chain.len() != before_last {
            chain = (0..before_last)
                .map(|count| self.prefix(count + 1, 2 + count))
                .collect::<Result<_>>()?;
        }
        let mut layers = Vec::new();
        let ghosted = self.trace_ghosts(frame, progress)?;
        let scene = ghosted.as_ref().map_or(frame, |(scene, _)| scene);
        if ghosted.is_some() {
            layers.push(GlareLayer {
                name: "glare.ghosts".to_string(),
                image: difference(scene.image(), frame.image()),
            });
        }
        let mut before: Option<Image> = None;
        for (prefix, name) in chain.iter_mut().zip(&names) {
            prefix.set_cancel_token(self.cancel_token());
            let after = prefix.apply(scene, &whole, progress)?.image;
            let base = before.as_ref().unwrap_or(scene.image());
            layers.push(GlareLayer {
                name: name.clone(),
                image: difference(&after, base),
            });
            before = Some(after);
        }
        // The last effect's layer is counted from the chain before it, or
        // from the scene the chain spreads.
        let base = match (before, names.last()) {
            (Some(image), _) => Some(image),
            (None, Some(_)) => Some(scene.image().clone()),
            (None, None) => None,
        };
        let mut applied = self.apply_after_ghosts(frame, ghosted, &whole, progress)?;
        if self.holds_layer_chains(crate::image::Shape::of(frame.image())) {
            self.layer_chain = chain;
        }
        if let (Some(name), Some(base)) = (names.last(), base) {
            layers.push(GlareLayer {
                name: name.clone(),
                image: difference(&applied.image, &base),
            });
        }
        layers.push(GlareLayer {
            name: "glare".to_string(),
            image: difference(&applied.image, frame.image()),
        });
        if options.glare_only {
            applied.image = layers[layers.len() - 1].image.clone();
            applied.image.alpha = frame.image().alpha.clone();
        }
        Ok((applied, layers))
    }
}

#[cfg(test)]
mod tests {
    use super::names;

    #[test]
    fn a_second_effect_of_a_type_is_numbered() {
        assert_eq!(
            names(["bloom", "aperture", "bloom", "bloom"].into_iter()),
            [
                "glare.bloom",
                "glare.aperture",
                "glare.bloom2",
                "glare.bloom3"
            ]
        );
    }
}
