//! PIZ's 2-D Haar wavelet (`ImfWav`), undone: levels from the coarsest,
//! pairs of samples from their average and difference, in 14-bit
//! arithmetic when every value fits (exact, no wrap), else modulo 2¹⁶.

fn pair14(l: u16, h: u16) -> (u16, u16) {
    let (ls, hi) = (i32::from(l as i16), i32::from(h as i16));
    let a = ls + (hi & 1) + (hi >> 1);
    (a as i16 as u16, (a - hi) as i16 as u16)
}

fn pair16(l: u16, h: u16) -> (u16, u16) {
    let (m, d) = (i32::from(l), i32::from(h));
    let b = (m - (d >> 1)) & 0xffff;
    let a = (d + b - 0x8000) & 0xffff;
    (a as u16, b as u16)
}

/// Undoes the wavelet of an `nx`×`ny` plane whose samples lie `ox` apart
/// in x and `oy` apart in y in `values`; `max` is the largest value the
/// lookup table gave (14-bit arithmetic below 2¹⁴).
pub(super) fn decode(values: &mut [u16], nx: usize, ox: usize, ny: usize, oy: usize, max: u16) {
    if max < (1 << 14) {
        decode_with(values, (nx, ox, ny, oy), pair14);
    } else {
        decode_with(values, (nx, ox, ny, oy), pair16);
    }
}

/// [`decode`] with one pair function, inlined.
#[inline(always)]
fn decode_with(
    values: &mut [u16],
    (nx, ox, ny, oy): (usize, usize, usize, usize),
    pair: impl Fn(u16, u16) -> (u16, u16),
) {
    let n = nx.min(ny);
    let mut p = 1;
    while p <= n {
        p <<= 1;
    }
    p >>= 1;
    let mut p2 = p;
    p >>= 1;
    while p >= 1 {
        let (ox1, oy1, ox2, oy2) = (ox * p, oy * p, ox * p2, oy * p2);
        let ey = oy * (ny - p2);
        let mut py = 0;
        while py <= ey {
            let ex = py + ox * (nx - p2);
            let mut px = py;
            while px <= ex {
                let (p01, p10) = (px + ox1, px + oy1);
                let p11 = p10 + ox1;
                let (i00, i10) = pair(values[px], values[p10]);
                let (i01, i11) = pair(values[p01], values[p11]);
                (values[px], values[p01]) = pair(i00, i01);
                (values[p10], values[p11]) = pair(i10, i11);
                px += ox2;
            }
            if nx & p != 0 {
                let p10 = px + oy1;
                (values[px], values[p10]) = pair(values[px], values[p10]);
            }
            py += oy2;
        }
        if ny & p != 0 {
            let ex = py + ox * (nx - p2);
            let mut px = py;
            while px <= ex {
                let p01 = px + ox1;
                (values[px], values[p01]) = pair(values[px], values[p01]);
                px += ox2;
            }
        }
        p2 = p;
        p >>= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// OpenEXR's `wenc14` and `wenc16`, to encode what the test decodes.
    fn encode14(a: u16, b: u16) -> (u16, u16) {
        let (a, b) = (i32::from(a as i16), i32::from(b as i16));
        let m = (a + b) >> 1;
        let d = a - b;
        (m as i16 as u16, d as i16 as u16)
    }

    fn encode16(a: u16, b: u16) -> (u16, u16) {
        let (ao, b) = ((i32::from(a) + 0x8000) & 0xffff, i32::from(b));
        let mut m = (ao + b) >> 1;
        let d = ao - b;
        if d < 0 {
            m = (m + 0x8000) & 0xffff;
        }
        (m as u16, (d & 0xffff) as u16)
    }

    #[test]
    fn pairs_come_back_from_their_average_and_difference() {
        for (a, b) in [(0u16, 0u16), (5, 9), (16000, 3), (100, 16383)] {
            let (l, h) = encode14(a, b);
            assert_eq!(pair14(l, h), (a, b));
        }
        for (a, b) in [(0u16, 0u16), (65535, 1), (40000, 30000), (7, 65000)] {
            let (l, h) = encode16(a, b);
            assert_eq!(pair16(l, h), (a, b), "{a} {b}");
        }
    }
}
