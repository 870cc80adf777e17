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
    /// The radius of a square about the centre left out (the lamps'
    /// window, which they add apart), if any.
    pub hole: Option<usize>,
}

impl Placement<'_> {
    /// Kernel row `j`, wrapped into a row of the period (`out`, zeros
    /// elsewhere); the centre weight (or the hole) left out where the
    /// engine applies it itself.
    pub fn row<T: From<f32> + Default + Copy>(&self, j: usize, out: &mut [T]) {
        let (kw, kh) = self.size;
        let px = out.len();
        let cx = kw / 2;
        let row = &self.plane[j * kw..(j + 1) * kw];
        let at = |i: usize| (i + px - cx) % px;
        if kw <= px {
            // Two runs, the centre's left and right halves, without a
            // division per value.
            let (left, right) = row.split_at(cx);
            out[kw - cx..px - cx].fill(T::default());
            for (o, &v) in out[px - cx..].iter_mut().zip(left) {
                *o = T::from(v);
            }
            for (o, &v) in out[..kw - cx].iter_mut().zip(right) {
                *o = T::from(v);
            }
        } else {
            out.fill(T::default());
            for (i, &v) in row.iter().enumerate() {
                out[at(i)] = T::from(v);
            }
        }
        if let Some(r) = self.hole.filter(|&r| j.abs_diff(kh / 2) <= r) {
            for i in cx - r..=cx + r {
                out[at(i)] = T::default();
            }
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
                    hole: None,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_lands_where_its_index_wraps_without_its_hole_and_centre() {
        let (kw, kh) = (7, 5);
        let plane: Vec<f32> = (0..kw * kh).map(|i| i as f32 + 1.0).collect();
        for px in [7, 8, 12] {
            for (centre, hole) in [
                (Centre::Include, None),
                (Centre::Leave, None),
                (Centre::Include, Some(1)),
            ] {
                let placed = Placement {
                    plane: &plane,
                    size: (kw, kh),
                    centre,
                    hole,
                };
                for j in 0..kh {
                    let mut expected = vec![0.0f64; px];
                    for i in 0..kw {
                        let left_out = hole
                            .is_some_and(|r| i.abs_diff(3) <= r && j.abs_diff(2) <= r)
                            || (centre == Centre::Leave && (i, j) == (3, 2));
                        if !left_out {
                            expected[(i + px - 3) % px] = f64::from(plane[j * kw + i]);
                        }
                    }
                    let mut out = vec![-1.0f64; px];
                    placed.row(j, &mut out);
                    assert_eq!(out, expected, "px {px}, row {j}, {centre:?}, {hole:?}");
                }
            }
        }
    }
}
