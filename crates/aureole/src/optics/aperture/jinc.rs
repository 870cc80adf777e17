//! 2J₁(z)/z, a disc's transform over its area: exactly, and from a table
//! to 10⁻⁶, since a spot's transform is evaluated at every sample of every
//! near pixel, for every speck of dust.

use std::sync::OnceLock;

/// 2J₁(z)/z.
pub(crate) fn jinc(z: f64) -> f64 {
    if z.abs() < 1e-6 {
        1.0
    } else {
        2.0 * crate::math::j1(z) / z
    }
}

/// Nodes per unit of z, and where the table ends (beyond, libm): its
/// values in 48 KB, which stay in the first-level cache.
const PER_UNIT: f64 = 128.0;
const END: f64 = 16.0;

/// Where [`crate::math::j1_far`] ends.
const FAR_END: f64 = 1e5;

/// How far from the point of a Taylor expansion z may lie: the third
/// order's term is below (1/4)³/6·max|jinc‴| < 10⁻³ there.
pub(super) const TAYLOR_REACH: f64 = 0.25;

/// 2J₁(z)/z and its first two derivatives: −2J₂(z)/z and
/// −2J₁(z)/z + 6J₂(z)/z², J₂ = 2J₁/z − J₀.
fn exact(z: f64) -> [f64; 3] {
    if z.abs() < 1e-3 {
        // The series: 1 − z²/8 + z⁴/192.
        let z2 = z * z;
        return [
            1.0 - z2 / 8.0 + z2 * z2 / 192.0,
            -z / 4.0 + z * z2 / 48.0,
            -0.25 + z2 / 16.0,
        ];
    }
    let (j0, j1) = (libm::j0(z), crate::math::j1(z));
    let j2 = 2.0 * j1 / z - j0;
    [
        2.0 * j1 / z,
        -2.0 * j2 / z,
        -2.0 * j1 / z + 6.0 * j2 / (z * z),
    ]
}

/// 2J₁(z)/z at z = |q|·`radius` for END ≤ z < FAR_END and every |q| of
/// `q`, into `out` (other z are computed at END, to be replaced), four at
/// once with AVX2: the values [`Table::values`] takes beyond the table.
#[inline(always)]
fn far_all(q: &[f64], radius: f64, out: &mut [f64]) {
    for (o, &q) in out.iter_mut().zip(q) {
        let z = (q * radius).max(END);
        *o = 2.0 * crate::math::j1_far(z) / z;
    }
}

pub(super) struct Table(Vec<[f64; 3]>);

pub(super) fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(|| {
        Table(
            (0..=(END * PER_UNIT) as usize + 1)
                .map(|k| exact(k as f64 / PER_UNIT))
                .collect(),
        )
    })
}

impl Table {
    /// 2J₁(z)/z for z ≥ 0, to 10⁻⁶: interpolated by the cubic that
    /// matches the values and slopes at the nodes either side.
    pub(super) fn value(&self, z: f64) -> f64 {
        if z >= END {
            return jinc(z);
        }
        let position = z * PER_UNIT;
        let k = position as usize;
        let t = position - k as f64;
        let (a, b) = (self.0[k], self.0[k + 1]);
        let h = 1.0 / PER_UNIT;
        let (h00, h10) = (
            (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t),
            t * (1.0 - t) * (1.0 - t),
        );
        let (h01, h11) = (t * t * (3.0 - 2.0 * t), t * t * (t - 1.0));
        h00 * a[0] + h10 * h * a[1] + h01 * b[0] + h11 * h * b[1]
    }

    /// [`Table::value`] at z = |q|·`radius` for every |q| of `q`, into
    /// `out`, with the same bits: those beyond the table, most of a large
    /// spot's, in vectors ([`far_all`]), the others one at a time.
    pub(super) fn values(&self, q: &[f64], radius: f64, out: &mut [f64]) {
        crate::convolve::widest(
            #[inline(always)]
            || far_all(q, radius, out),
        );
        for (o, &q) in out.iter_mut().zip(q) {
            let z = q * radius;
            if !(END..FAR_END).contains(&z) {
                *o = self.value(z);
            }
        }
    }

    /// The value and the first two derivatives at z ≥ 0: those of the
    /// nearest node, carried to z by their Taylor series.
    pub(super) fn taylor(&self, z: f64) -> [f64; 3] {
        if z >= END {
            return exact(z);
        }
        let k = (z * PER_UNIT).round() as usize;
        let [v, d1, d2] = self.0[k];
        let dz = z - k as f64 / PER_UNIT;
        [v + dz * (d1 + 0.5 * dz * d2), d1 + dz * d2, d2]
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_table_is_jinc_and_its_derivatives() {
        let table = super::table();
        for i in 0..200_000 {
            let z = i as f64 * 1e-4;
            let exact = super::exact(z);
            assert!((table.value(z) - exact[0]).abs() < 1e-6, "{z}");
            let taylor = table.taylor(z);
            assert!((taylor[0] - exact[0]).abs() < 1e-6, "{z}");
            assert!((taylor[1] - exact[1]).abs() < 1e-3, "{z}");
        }
        // The derivatives against differences of the values.
        for z in [0.5, 3.0, 7.7, 15.0, 20.0] {
            let h = 1e-5;
            let [_, first, second] = super::exact(z);
            let slope = (super::exact(z + h)[0] - super::exact(z - h)[0]) / (2.0 * h);
            let bend = (super::exact(z + h)[1] - super::exact(z - h)[1]) / (2.0 * h);
            assert!(
                (first - slope).abs() < 1e-8 && (second - bend).abs() < 1e-8,
                "{z}"
            );
        }
    }
}
