//! Where a kernel sits in the period of an FFT convolution: its centre at
//! index (0, 0), the rest wrapped around, so that the convolution is
//! centred. Both engines place their kernels here.

use super::Centre;

/// A kernel plane (row-major, centre at its middle) as the period sees it.
pub(crate) struct Placement<'a> {
    pub plane: &'a [f32],
    /// Width, height.
    pub size: (usize, usize),
    pub centre: Centre,
}

impl Placement<'_> {
    /// Kernel row `j`, wrapped into a row of the period (`out`, zeros
    /// elsewhere); the centre weight left out where the engine applies it
    /// itself.
    pub fn row<T: From<f32> + Default + Copy>(&self, j: usize, out: &mut [T]) {
        let (kw, kh) = self.size;
        let px = out.len();
        let cx = kw / 2;
        out.iter_mut().for_each(|v| *v = T::default());
        for (i, &v) in self.plane[j * kw..(j + 1) * kw].iter().enumerate() {
            out[(i + px - cx) % px] = T::from(v);
        }
        if self.centre == Centre::Leave && j == kh / 2 {
            out[0] = T::default();
        }
    }

    /// The row of a period of `py` rows that kernel row `j` lands on.
    pub fn period_row(&self, j: usize, py: usize) -> usize {
        (j + py - self.size.1 / 2) % py
    }

    /// Each of `planes`' weight left out ([`Placement::left_out`]).
    pub fn left_out_of(planes: &[&[f32]], size: (usize, usize), centre: Centre) -> Vec<f32> {
        planes
            .iter()
            .map(|plane| {
                Placement {
                    plane,
                    size,
                    centre,
                }
                .left_out()
            })
            .collect()
    }

    /// The weight the engine leaves out and applies exactly: the centre's,
    /// or 0 when the centre is convolved.
    pub fn left_out(&self) -> f32 {
        let (kw, kh) = self.size;
        match self.centre {
            Centre::Leave => self.plane[(kh / 2) * kw + kw / 2],
            Centre::Include => 0.0,
        }
    }
}
