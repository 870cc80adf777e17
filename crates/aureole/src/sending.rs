//! What sends the light a kernel spreads: a pixel's square or a point.

/// What sends the light a kernel spreads (docs/physics.md §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sending {
    /// A pixel of an image, whose light leaves its whole square: the
    /// kernel an image is convolved with, the PSF averaged over the
    /// sending pixel's area as well as the receiving one's. A frame
    /// rendered at 4K and reduced to 1080p then looks as the frame
    /// rendered at 1080p.
    #[default]
    Pixel,
    /// A point of light at the centre pixel's centre: the PSF as an optics
    /// program gives it (or a camera photographs a star), each pixel
    /// averaging it over its own area.
    Point,
}
