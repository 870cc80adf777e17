//! A frame's planes as half floats, for the trip up to the device: half
//! the bytes, where every value is one exactly (as every value decoded
//! from a half-float EXR is).

use rayon::prelude::*;

use crate::convolve::simd::widest;

/// Values a thread converts at a time.
const CHUNK: usize = 1 << 16;

/// `planes` one after another as half floats into `halves` (made as long
/// as they are, and one more for an odd count: two to a word), when every
/// value is one exactly, as every value decoded from a half-float EXR is;
/// `false` at the first that is not.
pub(super) fn as_halves(planes: &[&[f32]], halves: &mut Vec<u16>) -> bool {
    let count: usize = planes.iter().map(|plane| plane.len()).sum();
    // Where the memory is not to be had, the planes go up as they are.
    if crate::image::grow_zeroed(halves, count + count % 2).is_err() {
        return false;
    }
    let mut rest = halves.as_mut_slice();
    for plane in planes {
        let (these, after) = rest.split_at_mut(plane.len());
        // Without branches, so that the loop takes the CPU's vectors: a
        // 4K plane in 11 ms on one core, where half::f16::from_f32 took 44.
        let exact = these
            .par_chunks_mut(CHUNK)
            .zip(plane.par_chunks(CHUNK))
            .all(|(out, values)| {
                widest(|| {
                    let mut exact = true;
                    for (h, &v) in out.iter_mut().zip(values) {
                        let (bits, is_half) = half_of(v);
                        *h = bits;
                        exact &= is_half;
                    }
                    exact
                })
            });
        if !exact {
            return false;
        }
        rest = after;
    }
    rest.fill(0);
    true
}

/// The bits of the half float `v` is, and whether it is one exactly
/// (zeros, normals, subnormals and infinities of the halves' range with no
/// bits beyond theirs; never a NaN).
#[inline(always)]
fn half_of(v: f32) -> (u16, bool) {
    let bits = v.to_bits();
    let magnitude = bits & 0x7fff_ffff;
    let sign = (bits >> 16) & 0x8000;
    let exponent = magnitude >> 23;
    let mantissa = magnitude & 0x7f_ffff;
    // 2⁻¹⁴ ≤ |v| < 2¹⁶, its last 13 mantissa bits zero.
    let normal = exponent.wrapping_sub(113) <= 29 && mantissa & 0x1fff == 0;
    // 2⁻²⁴ ≤ |v| < 2⁻¹⁴: the half's mantissa is the significand shifted.
    let shift = 126u32.wrapping_sub(exponent).min(31);
    let significand = 0x80_0000 | mantissa;
    let subnormal = exponent.wrapping_sub(103) <= 9 && significand & ((1u32 << shift) - 1) == 0;
    let infinite = magnitude == 0x7f80_0000;
    let half = if normal {
        (exponent.wrapping_sub(112) << 10) | (mantissa >> 13)
    } else {
        0
    };
    let half = if subnormal {
        significand >> shift
    } else {
        half
    };
    let half = if infinite { 0x7c00 } else { half };
    (
        (sign | half) as u16,
        normal | subnormal | infinite | (magnitude == 0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use half::f16;

    #[test]
    fn every_half_float_is_found_and_nothing_else() {
        for bits in 0..=u16::MAX {
            let half = f16::from_bits(bits);
            if !half.is_nan() {
                assert_eq!(half_of(half.to_f32()), (bits, true), "{bits:#06x}");
            }
        }
        // Beyond the range, between two halves, below the least, NaN.
        for v in [
            65536.0,
            1e30,
            0.1,
            1.0 + 2f32.powi(-11),
            2f32.powi(-25),
            1e-30,
            f32::NAN,
        ] {
            assert!(!half_of(v).1, "{v}");
            assert!(!half_of(-v).1, "{}", -v);
        }
    }

    #[test]
    fn planes_of_half_floats_go_up_as_their_bits() {
        let tiny = 2f32.powi(-24);
        let first = [
            0.0,
            -0.0,
            1.0,
            0.099975586,
            65504.0,
            f32::INFINITY,
            tiny,
            -3.5,
        ];
        let second = [1024.0, 2.0f32.powi(-14)];
        // Into a buffer kept from a longer frame, its words stale.
        let halves_of = |planes: &[&[f32]]| {
            let mut halves = vec![0xffffu16; 13];
            as_halves(planes, &mut halves).then_some(halves)
        };
        let halves = halves_of(&[&first, &second]).unwrap();
        assert_eq!(halves.len(), 10);
        let bits = [
            0x0000, 0x8000, 0x3c00, 0x2e66, 0x7bff, 0x7c00, 0x0001, 0xc300,
        ];
        assert_eq!(halves[..8], bits);
        assert_eq!(halves[8..], [0x6400, 0x0400]);
        let odd = halves_of(&[&first[..3]]).unwrap();
        assert_eq!(odd, [0x0000, 0x8000, 0x3c00, 0]);
        // 0.1, a half's neighbour plus a bit, and a value beyond the
        // halves' range are not half floats.
        for not in [0.1, 1.0 + 2f32.powi(-11), 65536.0, tiny / 2.0] {
            assert!(halves_of(&[&first, &[not]]).is_none(), "{not}");
        }
    }
}
