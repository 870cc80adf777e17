//! Elementary functions for the kernel rasterisers' inner loops, where a
//! full-frame 4K kernel evaluates them tens of millions of times: each a
//! short polynomial in a few multiplications and additions, within a few
//! ulp of the correctly rounded value (the tests bound each against
//! `libm`), and deterministic as `libm` is: IEEE `+ − × ÷` in f64 only, no
//! fused multiply-add and no platform library, so every machine computes
//! the same bits.

use std::f64::consts::{FRAC_PI_2, PI};

/// Adding and subtracting this rounds an f64 below 2⁵¹ in magnitude to the
/// nearest whole number (ties to even) in the default rounding mode,
/// without a call to `round`.
const ROUNDER: f64 = 6_755_399_441_055_744.0;

/// ln 2 split so that k·[`LN2_HI`] is exact for |k| < 2²⁰ (its low 32 bits
/// are zero; fdlibm's split).
const LN2_HI: f64 = 0.6931471803691238;
const LN2_LO: f64 = 1.9082149292705877e-10;

/// π/2 = [`HALF_PI_HI`] + [`HALF_PI_LO`] to about 2⁻¹⁰⁶.
const HALF_PI_HI: f64 = FRAC_PI_2;
const HALF_PI_LO: f64 = 6.123_233_995_736_766e-17;

/// 2^k for −1022 ≤ k ≤ 1023.
#[inline(always)]
fn two_to(k: i64) -> f64 {
    f64::from_bits((k.wrapping_add(1023) as u64) << 52)
}

/// The nearest whole number to `v` (|v| < 2⁵¹), ties to even, as an f64
/// and as an integer: `v` + [`ROUNDER`] holds it in the low bits of its
/// representation, which vector units read without an f64-to-integer
/// conversion (AVX2 has none).
#[inline(always)]
pub(crate) fn nearest_and_whole(v: f64) -> (f64, i64) {
    let shifted = v + ROUNDER;
    (
        shifted - ROUNDER,
        shifted.to_bits().wrapping_sub(ROUNDER.to_bits()) as i64,
    )
}

/// `a` where `c` holds, else `b`: both sides computed, one chosen, so that
/// a loop of the functions below has no branch and takes vectors.
#[inline(always)]
fn pick(c: bool, a: f64, b: f64) -> f64 {
    if c {
        a
    } else {
        b
    }
}

/// eˣ within 2 ulp; 0 below −745.2 (where it underflows), ∞ above 709.8.
/// Without branches (every case computed, one chosen), so that loops of it
/// take vectors.
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    let (k, whole) = nearest_and_whole(x * std::f64::consts::LOG2_E);
    // |r| ≤ ln2/2: the Taylor series to r¹³/13! leaves 4·10⁻¹⁸. Its terms
    // from r² on are summed by Estrin's scheme, products of independent
    // pairs rather than one chain of thirteen, then added to 1 + r.
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let pair = |a: f64, b: f64| a + b * r;
    let tail = pair(1.0 / 2.0, 1.0 / 6.0)
        + r2 * pair(1.0 / 24.0, 1.0 / 120.0)
        + r4 * (pair(1.0 / 720.0, 1.0 / 5040.0) + r2 * pair(1.0 / 40320.0, 1.0 / 362_880.0))
        + r8 * (pair(1.0 / 3_628_800.0, 1.0 / 39_916_800.0)
            + r2 * pair(1.0 / 479_001_600.0, 1.0 / 6_227_020_800.0));
    let p = 1.0 + (r + r2 * tail);
    // Subnormal results are scaled in two steps and rounded once, at the
    // second; 2¹⁰²⁴ as 2¹⁰²³·2.
    let (low, high) = (whole < -1021, whole > 1023);
    let shift = if low {
        1000
    } else if high {
        -1
    } else {
        0
    };
    let second = pick(low, two_to(-1000), pick(high, 2.0, 1.0));
    let value = p * two_to(whole.wrapping_add(shift)) * second;
    let outside = pick(x.is_nan(), x, pick(x > 0.0, f64::INFINITY, 0.0));
    pick(x > -745.2 && x < 709.78, value, outside)
}

/// ln x within 2 ulp for positive finite x; −∞ at 0, NaN below. Without
/// branches, as [`exp`].
#[inline(always)]
pub fn ln(x: f64) -> f64 {
    // A subnormal x is scaled into the normal range first.
    let subnormal = x < f64::MIN_POSITIVE;
    let bits = pick(subnormal, x * two_to(54), x).to_bits();
    let m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | (1023 << 52));
    let big = m > std::f64::consts::SQRT_2;
    let m = pick(big, m * 0.5, m);
    // The exponent, read as an f64 from a representation of 2⁵² + e + 1023
    // rather than converted (AVX2 converts no 64-bit integers).
    let biased = ((bits >> 52) & 0x7ff) + u64::from(big);
    let e = f64::from_bits(0x4330_0000_0000_0000 | biased) - (4_503_599_627_370_496.0 + 1023.0);
    // ln m = 2 atanh s with s = f/(2 + f), |s| ≤ 0.172, written as
    // f − s(f − R) (f exact) with R ≈ Σ 2s²ʲ/(2j + 1): fdlibm's minimax
    // coefficients (error below 2⁻⁵⁸·⁴⁵), its even and odd terms summed
    // apart.
    const LG: [f64; 7] = [
        0.6666666666666735,
        0.3999999999940942,
        0.2857142874366239,
        0.22222198432149784,
        0.1818357216161805,
        0.15313837699209373,
        0.14798198605116586,
    ];
    let f = m - 1.0;
    let s = f / (2.0 + f);
    let z = s * s;
    let w = z * z;
    let odd = z * (LG[0] + w * (LG[2] + w * (LG[4] + w * LG[6])));
    let even = w * (LG[1] + w * (LG[3] + w * LG[5]));
    let big_r = odd + even;
    let value = e * LN2_HI + (f - (s * (f - big_r) - e * LN2_LO));
    let value = pick(subnormal, value - 54.0 * std::f64::consts::LN_2, value);
    let outside = pick(
        x == f64::INFINITY,
        x,
        pick(x == 0.0, f64::NEG_INFINITY, f64::NAN),
    );
    pick(x > 0.0 && x < f64::INFINITY, value, outside)
}

/// (sin x, cos x) to within 4·10⁻¹⁶ for |x| < 10⁵ in plain arithmetic,
/// so that rows of them vectorise and give the same bytes everywhere:
/// x less the nearest multiple n of π/2, in two parts, then the Taylor
/// series on [−π/4, π/4], turned by n quarter turns.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    const HIGH: f64 = 1.570_796_326_734_125_6;
    const LOW: f64 = 6.077_100_506_506_192e-11;
    let shifted = x * std::f64::consts::FRAC_2_PI + ROUNDER;
    let quarter = shifted.to_bits();
    let n = shifted - ROUNDER;
    let y = (x - n * HIGH) - n * LOW;
    let y2 = y * y;
    let sin = y
        * (1.0
            + y2 * (-1.0 / 6.0
                + y2 * (1.0 / 120.0
                    + y2 * (-1.0 / 5040.0
                        + y2 * (1.0 / 362_880.0
                            + y2 * (-1.0 / 39_916_800.0
                                + y2 * (1.0 / 6_227_020_800.0
                                    + y2 * (-1.0 / 1_307_674_368_000.0))))))));
    let cos = 1.0
        + y2 * (-0.5
            + y2 * (1.0 / 24.0
                + y2 * (-1.0 / 720.0
                    + y2 * (1.0 / 40_320.0
                        + y2 * (-1.0 / 3_628_800.0
                            + y2 * (1.0 / 479_001_600.0
                                + y2 * (-1.0 / 87_178_291_200.0
                                    + y2 * (1.0 / 20_922_789_888_000.0))))))));
    // The quarter turns by masks, not branches, which would be taken at
    // random.
    const SIGN: u64 = 1 << 63;
    let odd = 0u64.wrapping_sub(quarter & 1);
    let half = (quarter & 2) << 62;
    let (sin, cos) = (sin.to_bits(), cos.to_bits());
    let s = (sin & !odd) | (cos & odd);
    let c = (cos & !odd) | ((sin ^ SIGN) & odd);
    (f64::from_bits(s ^ half), f64::from_bits(c ^ half))
}

/// (sin x, cos x) for any x: [`sin_cos`] where it holds (|x| < 10⁵),
/// libm's reduction beyond. For phases computed once per row or per run of
/// pixels, where the branch is taken the same way every time.
#[inline]
pub fn sin_cos_wide(x: f64) -> (f64, f64) {
    if x.abs() < 1e5 {
        sin_cos(x)
    } else {
        libm::sincos(x)
    }
}

/// J₁(x), the Bessel function of the first kind of order one, within
/// 2·10⁻¹⁶ of libm's for 8 ≤ |x| < 10⁵ and libm's own elsewhere. There,
/// as libm, J₁ = √(2/(πx))·(P₁ cos(x − 3π/4) − Q₁ sin(x − 3π/4)) with
/// fdlibm's rational approximations of P₁ and Q₁, but with sin x and cos x
/// from one [`sin_cos`] instead of libm's three reduced calls (sin x,
/// cos x, and cos 2x, which keeps J₁'s relative precision about its zeros;
/// its absolute error, all a pupil's transform needs, stays within
/// 2·10⁻¹⁶). A round stop's near field evaluates it at every sample.
#[inline]
pub fn j1(x: f64) -> f64 {
    let a = x.abs();
    if !(8.0..1e5).contains(&a) {
        return libm::j1(x);
    }
    let value = j1_far(a);
    if x < 0.0 {
        -value
    } else {
        value
    }
}

/// [`j1`] for 8 ≤ `a` < 10⁵ alone, without a branch: rows of it take
/// vectors, with the same bits.
#[inline(always)]
pub fn j1_far(a: f64) -> f64 {
    let (s, c) = sin_cos(a);
    let z = 1.0 / (a * a);
    let (pr, ps, qr, qs) = (&J1_PR8, &J1_PS8, &J1_QR8, &J1_QS8);
    let p = 1.0
        + (pr[0] + z * (pr[1] + z * (pr[2] + z * (pr[3] + z * (pr[4] + z * pr[5])))))
            / (1.0 + z * (ps[0] + z * (ps[1] + z * (ps[2] + z * (ps[3] + z * ps[4])))));
    let q = (0.375
        + (qr[0] + z * (qr[1] + z * (qr[2] + z * (qr[3] + z * (qr[4] + z * qr[5])))))
            / (1.0
                + z * (qs[0] + z * (qs[1] + z * (qs[2] + z * (qs[3] + z * (qs[4] + z * qs[5])))))))
        / a;
    FRAC_1_SQRT_PI * (p * (s - c) - q * (-s - c)) / a.sqrt()
}

/// The f64s of `bits`.
const fn bits<const N: usize>(bits: [u64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut k = 0;
    while k < N {
        out[k] = f64::from_bits(bits[k]);
        k += 1;
    }
    out
}

/// 1/√π.
const FRAC_1_SQRT_PI: f64 = f64::from_bits(0x3FE2_0DD7_5042_9B6D);

// P₁ − 1 and Q₁/s − 3/8 (s = 1/x) for x ≥ 8 as ratios of polynomials in
// s², from FreeBSD's e_j1.c, through the libm crate:
// Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
// Developed at SunSoft, a Sun Microsystems, Inc. business. Permission to
// use, copy, modify, and distribute this software is freely granted,
// provided that this notice is preserved.
// (Their bits, as printed there.)
const J1_PR8: [f64; 6] = bits([
    0x00000000_00000000,
    0x3FBDFFFF_FFFFFCCE,
    0x402A7A9D_357F7FCE,
    0x4079C0D4_652EA590,
    0x40AE457D_A3A532CC,
    0x40BEEA7A_C32782DD,
]);
const J1_PS8: [f64; 5] = bits([
    0x405C8D45_8E656CAC,
    0x40AC85DC_964D274F,
    0x40E20B86_97C5BB7F,
    0x40F7D42C_B28F17BB,
    0x40DE1511_697A0B2D,
]);
const J1_QR8: [f64; 6] = bits([
    0x00000000_00000000,
    0xBFBA3FFF_FFFFFDF3,
    0xC0304591_A26779F7,
    0xC087BCD0_53E4B576,
    0xC0C724E7_40F87415,
    0xC0E7A6D0_65D09C6A,
]);
const J1_QS8: [f64; 6] = bits([
    0x40642CA6_DE5BCDE5,
    0x40BE9162_D0D88419,
    0x4100579A_B0B75E98,
    0x4125F653_72869C19,
    0x412457D2_7719AD5C,
    0xC111F969_0EA5AA18,
]);

/// −ln cos x for |x| ≤ π/2, to within 6 ulp of its own value: where x is
/// small (the far, thin parts of a corona's rays, millions of samples) its
/// Taylor series, whose next term is below 10⁻¹⁸ of the sum there;
/// ln(1 − 2 sin²(x/2)) up to 1 (the digits a cosine near 1 loses);
/// −ln sin(π/2 − |x|) nearer π/2 (the difference taken in two parts, so
/// that a small cosine keeps its digits). Without branches, as [`exp`]:
/// the last two share one sine and one logarithm.
#[inline(always)]
pub fn neg_ln_cos(x: f64) -> f64 {
    let a = x.abs();
    let x2 = a * a;
    let series = x2
        * (1.0 / 2.0
            + x2 * (1.0 / 12.0
                + x2 * (1.0 / 45.0
                    + x2 * (17.0 / 2520.0 + x2 * (31.0 / 14175.0 + x2 * (691.0 / 467_775.0))))));
    let near = a <= 1.0;
    // HALF_PI_HI − a is exact by Sterbenz's lemma (a ∈ [1, π/2]); an a
    // an ulp beyond π/2 is a cosine of 0.
    let d = ((HALF_PI_HI - a) + HALF_PI_LO).max(0.0);
    let sine = sin_cos(pick(near, 0.5 * a, d)).0;
    // Near: −ln(1 + v), v = −2 sin²(x/2), the digits of a small v kept by
    // correcting for the rounding of 1 + v.
    let v = -2.0 * sine * sine;
    let u = 1.0 + v;
    let log = ln(pick(near, u, sine));
    let near_value = pick(u == 1.0, v, log + (v - (u - 1.0)) / u);
    pick(x2 <= 0.0025, series, pick(near, -near_value, -log))
}

/// The eight anchors of [`atan2`]: atan((2i + 1)/16), correctly rounded.
const ATAN_ANCHORS: [f64; 8] = [
    0.062_418_809_995_957_35,
    0.185_347_949_995_694_76,
    0.302_884_868_374_971_4,
    0.412_410_441_597_387_3,
    0.512_389_460_310_737_7,
    0.602_287_346_134_964_2,
    0.682_316_554_874_748_1,
    0.753_151_280_962_194_4,
];

/// atan2(y, x) within 2 ulp of π (in absolute terms, 5·10⁻¹⁶ rad), with
/// `libm`'s results at zeros, infinities and NaN.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    if atan2_is_plain(y, x) {
        atan2_plain(y, x)
    } else {
        libm::atan2(y, x)
    }
}

/// Whether [`atan2_plain`] gives [`atan2`] at (y, x): neither is 0,
/// infinite, NaN or beyond 10^±300.
#[inline(always)]
pub fn atan2_is_plain(y: f64, x: f64) -> bool {
    let (ax, ay) = (x.abs(), y.abs());
    let (small, large) = if ay > ax { (ax, ay) } else { (ay, ax) };
    small > 0.0 && large < f64::INFINITY && large <= 1e300 && small >= 1e-300
}

/// [`atan2`] where [`atan2_is_plain`], without branches, so that loops of
/// it take vectors (and elsewhere any number: those points are taken
/// again by [`atan2`]).
#[inline(always)]
pub fn atan2_plain(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let steep = ay > ax;
    let (small, large) = (pick(steep, ax, ay), pick(steep, ay, ax));
    let z = small / large;
    // z ∈ (0, 1]: atan z = atan c + atan((z − c)/(1 + zc)) about the
    // nearest anchor c = (2i + 1)/16, i = ⌊8z⌋ (at most 7), |t| ≤ 1/16;
    // atan t by its series to t¹⁷ (Estrin's scheme in t²) leaves 10⁻²⁴.
    // The anchor is chosen by comparisons, not by an index.
    let (mut c, mut anchor) = (1.0 / 16.0, ATAN_ANCHORS[0]);
    for (i, &a) in ATAN_ANCHORS.iter().enumerate().skip(1) {
        let above = z >= i as f64 / 8.0;
        c = pick(above, (2 * i + 1) as f64 / 16.0, c);
        anchor = pick(above, a, anchor);
    }
    let t = (z - c) / (1.0 + z * c);
    let u = t * t;
    let u2 = u * u;
    let u4 = u2 * u2;
    let pair = |a: f64, b: f64| a + b * u;
    let tail = pair(-1.0 / 3.0, 1.0 / 5.0)
        + u2 * pair(-1.0 / 7.0, 1.0 / 9.0)
        + u4 * (pair(-1.0 / 11.0, 1.0 / 13.0) + u2 * pair(-1.0 / 15.0, 1.0 / 17.0));
    let series = t + t * u * tail;
    let a = anchor + series;
    let a = pick(steep, (HALF_PI_HI - a) + HALF_PI_LO, a);
    let a = pick(x < 0.0, (PI - a) + 2.0 * HALF_PI_LO, a);
    pick(y < 0.0, -a, a)
}

/// base^exponent: for a whole exponent (the bloom's β = 2 to 5, Vos's
/// n = 2) by squaring, a tenth of `pow`'s time over the millions of pixels
/// of a full-frame kernel and within an ulp or two of it; else `pow`.
#[inline]
pub fn power(base: f64, exponent: f64) -> f64 {
    let whole = exponent.abs();
    if whole.fract() != 0.0 || whole > 64.0 {
        return libm::pow(base, exponent);
    }
    let (mut result, mut square, mut n) = (1.0, base, whole as u32);
    while n > 0 {
        if n & 1 == 1 {
            result *= square;
        }
        square *= square;
        n >>= 1;
    }
    if exponent < 0.0 {
        1.0 / result
    } else {
        result
    }
}

/// The `n` Gauss–Legendre nodes on [−1, 1] and their weights (Σ = 2):
/// Newton's method on P_n from the Chebyshev guesses, P_n by its
/// recurrence.
pub(crate) fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut nodes, mut weights) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n.div_ceil(2) {
        let mut x = libm::cos(std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5));
        let mut derivative = 1.0;
        for _ in 0..100 {
            let (p, dp) = legendre(n, x);
            derivative = dp;
            let step = p / dp;
            x -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
        nodes[i] = -x;
        nodes[n - 1 - i] = x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    (nodes, weights)
}

/// P_n(x) and P_n'(x).
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// |a − b| in units of b's last place.
    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        let ulp = f64::from_bits(b.abs().to_bits() + 1) - b.abs();
        (a - b).abs() / ulp.max(f64::from_bits(1))
    }

    #[test]
    fn sines_and_cosines_are_those_of_libm() {
        // Across the quarter turns' boundaries and out to the phases of
        // the farthest fringes (K r ≲ 10⁵ rad).
        let mut x = -20.0;
        while x < 1e5 {
            let (s, c) = sin_cos(x);
            let tolerance = 4e-16;
            assert!((s - libm::sin(x)).abs() <= tolerance, "sin {x}: {s}");
            assert!((c - libm::cos(x)).abs() <= tolerance, "cos {x}: {c}");
            x = if x < 1.0 { x + 0.0123 } else { x * 1.001 };
        }
        for k in -8..=8 {
            let x = f64::from(k) * std::f64::consts::FRAC_PI_4;
            let (s, c) = sin_cos(x);
            assert!(
                (s - libm::sin(x)).abs() < 1e-15 && (c - libm::cos(x)).abs() < 1e-15,
                "{x}"
            );
        }
    }

    #[test]
    fn bessel_j1_is_libms() {
        // Through the switch at 8, out to the switch at 10⁵ and beyond,
        // on both signs: libm's within 2·10⁻¹⁶ (J₁ ≤ 0.35 there), its own
        // bits elsewhere.
        let mut worst = 0f64;
        let mut x = 0.0;
        while x < 2e5 {
            for x in [x, -x] {
                let (ours, theirs) = (j1(x), libm::j1(x));
                if x.abs() < 8.0 || x.abs() >= 1e5 {
                    assert_eq!(ours.to_bits(), theirs.to_bits(), "{x}");
                }
                worst = worst.max((ours - theirs).abs());
            }
            x = if x < 20.0 { x + 0.001_7 } else { x * 1.000_3 };
        }
        assert!(worst <= 2e-16, "{worst:e}");
    }

    #[test]
    fn atan_anchors_are_the_arctangents() {
        for (i, &a) in ATAN_ANCHORS.iter().enumerate() {
            let c = (2 * i + 1) as f64 / 16.0;
            assert!(ulps(a, libm::atan(c)) <= 1.0, "{i}");
        }
    }

    #[test]
    fn exp_is_within_two_ulp_across_its_range() {
        let mut worst = 0f64;
        for i in 0..200_000 {
            let x = -745.0 + 1454.7 * i as f64 / 200_000.0;
            let e = libm::exp(x);
            if e >= f64::MIN_POSITIVE {
                worst = worst.max(ulps(exp(x), e));
            } else {
                // Subnormal: as many digits as the format keeps.
                assert!((exp(x) - e).abs() <= 2.0 * f64::from_bits(1), "{x}");
            }
        }
        assert!(worst <= 2.0, "{worst}");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-800.0), 0.0);
        assert_eq!(exp(800.0), f64::INFINITY);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert!(exp(f64::NAN).is_nan());
    }

    #[test]
    fn ln_is_within_two_ulp_across_its_range() {
        let mut worst = 0f64;
        for i in 0..200_000 {
            let x = libm::exp(-740.0 + 1449.0 * i as f64 / 200_000.0);
            worst = worst.max(ulps(ln(x), libm::log(x)));
        }
        for i in 1..100_000 {
            let x = 0.5 + i as f64 / 50_000.0;
            worst = worst.max(ulps(ln(x), libm::log(x)));
        }
        assert!(worst <= 2.0, "{worst}");
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f64::NEG_INFINITY);
        assert!(ln(-1.0).is_nan());
        assert!(ulps(ln(1e-310), libm::log(1e-310)) <= 2.0);
    }

    #[test]
    fn sin_cos_wide_is_libms_within_4e_16_at_any_phase() {
        let phases = (0..200_000).map(|i| -3e5 + 3.000_001 * f64::from(i));
        for x in phases.chain([1e5 - 1e-9, 1e5, -1e5, 1e12, 0.0, -0.0]) {
            let (s, c) = sin_cos_wide(x);
            let (ls, lc) = libm::sincos(x);
            assert!((s - ls).abs() <= 4e-16 && (c - lc).abs() <= 4e-16, "{x}");
        }
    }

    #[test]
    fn neg_ln_cos_is_minus_the_log_of_the_cosine() {
        let mut worst = 0f64;
        let small = (1..2000).map(|i| 1e-9 * 1.01f64.powi(i));
        let spread = (1..200_000).map(|i| FRAC_PI_2 * i as f64 / 200_000.0);
        for x in small.filter(|&x| x < 1.0).chain(spread) {
            // Near π/2 the cosine of the rounded x is what both take.
            let exact = if x <= 1.0 {
                // Within an ulp or two where ln(cos x) loses the digits of
                // a cosine near 1.
                -libm::log1p(-2.0 * libm::sin(0.5 * x).powi(2))
            } else {
                -libm::log(libm::sin((HALF_PI_HI - x) + HALF_PI_LO))
            };
            worst = worst.max(ulps(neg_ln_cos(x), exact));
            assert_eq!(neg_ln_cos(x), neg_ln_cos(-x));
        }
        assert!(worst <= 6.0, "{worst}");
        assert_eq!(neg_ln_cos(0.0), 0.0);
        // cos of the f64 nearest π/2 is 6.1·10⁻¹⁷, not 0.
        let edge = -libm::log(libm::cos(FRAC_PI_2));
        assert!(ulps(neg_ln_cos(FRAC_PI_2), edge) <= 2.0);
    }

    proptest! {
        #[test]
        fn atan2_is_within_two_ulp_of_pi(y in -1e6f64..1e6, x in -1e6f64..1e6, scale in -300i32..300) {
            let s = 10f64.powi(scale / 2);
            let (y, x) = (y * s, x * s);
            let d = (atan2(y, x) - libm::atan2(y, x)).abs();
            prop_assert!(d <= 5e-16, "atan2({y}, {x}): {d}");
        }

        #[test]
        fn exp_and_ln_agree_with_libm_anywhere(x in -700f64..700.0) {
            prop_assert!(ulps(exp(x), libm::exp(x)) <= 2.0, "exp({x})");
            let y = libm::exp(x);
            prop_assert!(ulps(ln(y), libm::log(y)) <= 2.0, "ln({y})");
        }
    }

    #[test]
    fn atan2_has_libms_results_on_the_axes_and_at_infinity() {
        for (y, x) in [
            (0.0, 1.0),
            (0.0, -1.0),
            (-0.0, -1.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (0.0, 0.0),
            (1.0, f64::INFINITY),
            (f64::INFINITY, 1.0),
            (1.0, -1.0),
            (-1.0, -1.0),
        ] {
            let (ours, theirs) = (atan2(y, x), libm::atan2(y, x));
            assert!(
                (ours - theirs).abs() <= 5e-16,
                "({y}, {x}): {ours} vs {theirs}"
            );
        }
        assert!(atan2(f64::NAN, 1.0).is_nan());
    }

    #[test]
    fn whole_powers_by_squaring_agree_with_pow() {
        for base in [1.0, 1.0 + 1e-9, 1.37, 2.0, 101.0, 7.3e6] {
            for exponent in [-2.0, -3.0, -5.0, -64.0, -2.5, 1.5, 4.0, -100.0] {
                let (fast, reference) = (power(base, exponent), libm::pow(base, exponent));
                assert!(
                    (fast - reference).abs() <= 8.0 * f64::EPSILON * reference.abs(),
                    "{base}^{exponent}: {fast} vs {reference}"
                );
            }
        }
    }

    #[test]
    fn nearest_rounds_ties_to_even() {
        for (v, whole) in [
            (2.5, 2),
            (3.5, 4),
            (-1.4, -1),
            (-2.5, -2),
            (1e15 + 0.75, 1e15 as i64 + 1),
        ] {
            assert_eq!(nearest_and_whole(v), (whole as f64, whole), "{v}");
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_of_degree_2n_minus_1_exactly() {
        for n in [2, 3, 5, 8, 17, 24] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n = {n}");
            for degree in 0..2 * n {
                let got: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(x, w)| w * x.powi(degree as i32))
                    .sum();
                let exact = if degree % 2 == 1 {
                    0.0
                } else {
                    2.0 / (degree as f64 + 1.0)
                };
                assert!(
                    (got - exact).abs() < 1e-12,
                    "n = {n}, x^{degree}: {got} vs {exact}"
                );
            }
        }
    }
}
