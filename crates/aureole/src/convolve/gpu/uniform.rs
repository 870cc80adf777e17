//! The uniforms every grid shader of the GPU engine reads.

/// The uniforms of the grid shaders (`Grid` in common.wgsl).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Uniform {
    pub(super) px: u32,
    pub(super) py: u32,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) planes: u32,
    pub(super) fractions: bool,
    pub(super) accumulate: bool,
    pub(super) leave_centre: bool,
    pub(super) halves: [u32; 2],
    pub(super) centre: [f32; 2],
    pub(super) lamps: u32,
    pub(super) weights: [f32; 2],
    pub(super) halves_up: bool,
}

impl Uniform {
    /// The words the shaders read, in `Grid`'s order.
    pub(super) fn words(&self) -> [u32; 20] {
        let scale = 1.0 / (self.px as f32 * self.py as f32);
        [
            self.px,
            self.py,
            self.width,
            self.height,
            self.planes,
            u32::from(self.fractions),
            u32::from(self.accumulate),
            u32::from(self.leave_centre),
            self.halves[0],
            self.halves[1],
            self.centre[0].to_bits(),
            self.centre[1].to_bits(),
            scale.to_bits(),
            self.lamps,
            self.weights[0].to_bits(),
            self.weights[1].to_bits(),
            u32::from(self.halves_up),
            0,
            0,
            0,
        ]
    }
}
