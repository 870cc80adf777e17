//! The rims of round stops and obstructions: each disc's ⟨J₁²⟩ term with
//! its fringes, their beats with concentric discs and with the edges that
//! end on a rim.

use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};

use super::{band, pixel_mean, Line, FRINGE_FLOOR, PLANES};
use crate::kernel::Sending;
use crate::math::sin_cos;
use crate::optics::aperture::pupil::{DiscTerm, EdgeTerm};

/// The most nodes of a wave's table of pixel means.
const MOST_NODES: usize = 1 << 16;

/// The discs' fringes. Far out a disc's amplitude is, by stationary
/// phase, s√R cos(z − 3π/4)/(πρ^{3/2}), z = 2πρR, ρ = r/(λf), so that
/// concentric discs add to their means R/(2π²ρ³) the waves −R sin 2z of
/// each and 2s₁s₂√(R₁R₂)(cos(z₁ − z₂) − sin(z₁ + z₂)) of each pair: waves
/// along the radius, each averaged over the square pixel as e^(iK n̂·δ),
/// K its wavenumber, n̂ = x/r. (Across a pixel the circle bends from its
/// tangent by p²/(8r): below 0.03 rad of phase beyond r_far.) Discs with
/// different centres are left incoherent: no stop has them.
pub(super) struct Fringes {
    /// Per disc, 2πR/f: z = that·r/λ.
    radii: Vec<f64>,
    /// Per line, its waves.
    lines: Vec<Vec<Wave>>,
    /// Per line, 1/λ.
    inverse_lambda: Vec<f64>,
    /// The step in u = min(|n̂_x|, |n̂_y|) of the waves' pixel means.
    step: f64,
    /// The edges that end on a disc's rim.
    rims: Vec<Rim>,
    focal: f64,
    /// How far out, mm, the fringes and the rims' beats can hold
    /// FRINGE_FLOOR of the light in a pixel.
    reach: f64,
}

/// A straight edge whose midpoint m lies on a disc's rim with its normal
/// along the radius: a vane's end on the stop or on the obstruction. About
/// the edge's ray, x ∥ ±(m − c), the disc's stationary point ±R x/|x| is
/// the edge itself, so that their fields' cross term does not oscillate:
/// with the edge's field s_k(i/|q|²)L(q·n̂)sinc(q·e/2)e^(−iq·m) and the
/// disc's as above, 2 Re(F_k Â_j*) = A (P₁ sin Φ₁ − P₂ sin Φ₂),
/// A = s_k s_j L(q·n̂) sinc(q·e/2) √R/(π|q|²ρ^{3/2}),
/// Φ_{1,2} = z ± q·d − 3π/4, d = m − c: each slow on its side of the
/// centre, and averaged over the square pixel by its phase's gradient,
/// P = the pixel's mean of e^(i2π(Rn̂ ± d)·δ/(λf)).
struct Rim {
    disc: usize,
    /// d, mm.
    offset: [f64; 2],
    normal: [f64; 2],
    along: [f64; 2],
    length: f64,
    /// Per line and plane: 2 s_k s_j L √R √(λ/f), in the units of
    /// [`FarField::discs`], times the line's share of the plane.
    weights: Vec<[f64; PLANES]>,
    /// Per line, P₁ at the angles θ = −π + i·step of n̂ up to 2π (P₂ is
    /// P₁ at θ + π, `half_turn` steps on).
    pixel: Vec<Vec<f64>>,
    step: f64,
    half_turn: usize,
    /// The beat can reach FRINGE_FLOOR in a pixel at r only within
    /// band/r^{5/2} of the edge's ray (mm), and r only within `reach`.
    band: f64,
    reach: f64,
}

impl Rim {
    /// The edges of `edges` that end on a disc of `discs`, in a pupil of
    /// `area` mm².
    fn find(
        edges: &[EdgeTerm],
        discs: &[DiscTerm],
        lines: &[Line],
        f: f64,
        pitch: f64,
        sending: Sending,
        area: f64,
    ) -> Vec<Rim> {
        let shortest = lines.iter().map(|l| l.lambda).fold(f64::INFINITY, f64::min);
        let longest = lines.iter().map(|l| l.lambda).fold(0.0, f64::max);
        let mut rims = Vec::new();
        for edge in edges {
            // An edge on a rim beats with it along its whole ray; a short
            // one elsewhere (a vane's end on another disc) with a phase
            // that turns along the ray, which the pixel's mean follows as
            // long as the edge's sinc is smooth across the pixel: its ray
            // two pixels wide or more.
            let short = edge.length <= shortest * f / (2.0 * pitch);
            for (j, disc) in discs.iter().enumerate() {
                let d = [
                    edge.middle[0] - disc.centre[0],
                    edge.middle[1] - disc.centre[1],
                ];
                let distance = libm::hypot(d[0], d[1]);
                let radial = (d[0] * edge.normal[1] - d[1] * edge.normal[0]).abs();
                let on_rim = (distance - disc.radius).abs() <= 1e-6 * disc.radius;
                if !(on_rim || short) || radial > 1e-9 * distance {
                    continue;
                }
                // P turns by at most 0.02 rad per step.
                let turn = PI * pitch * (disc.radius + distance) / (shortest * f);
                let half_turn = ((PI * turn / 0.02).ceil() as usize).clamp(32, 1 << 15);
                let step = PI / half_turn as f64;
                let amplitude = 2.0 * edge.sign * disc.sign * edge.length * disc.radius.sqrt();
                // The beat is at most L√R (λf)^{1/2} p²/(π² r^{5/2}·area) of
                // the light in a pixel, and 2/(κL|x·ê|) of that beside the
                // edge's ray, κ = 2π/(λf).
                let beat = edge.length * (disc.radius * longest * f).sqrt() * pitch * pitch
                    / (PI * PI * area * FRINGE_FLOOR);
                rims.push(Rim {
                    disc: j,
                    offset: d,
                    normal: edge.normal,
                    along: edge.along,
                    length: edge.length,
                    weights: lines
                        .iter()
                        .map(|line| line.weights(amplitude * (line.lambda / f).sqrt()))
                        .collect(),
                    pixel: lines
                        .iter()
                        .map(|line| {
                            (0..3 * half_turn + 2)
                                .map(|i| {
                                    let (sin, cos) = libm::sincos(-PI + i as f64 * step);
                                    let g = [disc.radius * cos + d[0], disc.radius * sin + d[1]];
                                    pixel_mean(pitch, sending, g.map(|g| g / (line.lambda * f)))
                                })
                                .collect()
                        })
                        .collect(),
                    step,
                    half_turn,
                    band: beat * 2.0 * longest * f / (TAU * edge.length),
                    reach: libm::pow(beat, 0.4),
                });
            }
        }
        rims
    }
}

/// The discs a wave is made of.
#[derive(Clone, Copy)]
enum Waveform {
    /// −sin 2z_j.
    Own(usize),
    /// −sin(z_j + z_k).
    Sum(usize, usize),
    /// cos(z_j − z_k).
    Difference(usize, usize),
}

/// One wave in one wavelength.
struct Wave {
    form: Waveform,
    /// Per plane: its amplitude, in the units of [`FarField::discs`],
    /// times the line's λ and its share of the plane.
    weights: [f64; PLANES],
    /// The mean of e^(iK n̂·δ) over the pixel at u = i·step.
    pixel: Vec<f64>,
}

/// Scratch space for one row's fringes.
#[derive(Default)]
pub(super) struct FringeRow {
    x: Vec<f64>,
    radius: Vec<f64>,
    /// Per pixel, √r.
    root: Vec<f64>,
    /// Per pixel, a rim's second wave.
    second: Vec<f64>,
    /// Per pixel, the angle of x, for the rims.
    angle: Vec<f64>,
    node: Vec<usize>,
    fraction: Vec<f64>,
    /// Per disc, sin z and cos z along the row.
    sines: Vec<Vec<f64>>,
    cosines: Vec<Vec<f64>>,
    wave: Vec<f64>,
    /// The first pixel within the fringes' reach.
    start: usize,
    /// Per plane, the fringes' sum in the pixels from `start` on.
    sums: Vec<Vec<f64>>,
}

impl Fringes {
    pub(super) fn new(
        discs: &[DiscTerm],
        edges: &[EdgeTerm],
        lines: &[Line],
        f: f64,
        pitch: f64,
        sending: Sending,
        area: f64,
    ) -> Fringes {
        // Each wave's form, amplitude and R₁ ± R₂ (or 2R), the same in
        // every line.
        let mut forms = Vec::new();
        for (j, a) in discs.iter().enumerate() {
            forms.push((Waveform::Own(j), 2.0 * a.radius, 2.0 * a.radius));
            for (k, b) in discs.iter().enumerate().skip(j + 1) {
                if a.centre != b.centre {
                    continue;
                }
                let amplitude = 4.0 * a.sign * b.sign * (a.radius * b.radius).sqrt();
                forms.push((Waveform::Sum(j, k), amplitude, a.radius + b.radius));
                forms.push((
                    Waveform::Difference(j, k),
                    amplitude,
                    (a.radius - b.radius).abs(),
                ));
            }
        }
        let shortest = lines.iter().map(|l| l.lambda).fold(f64::INFINITY, f64::min);
        let widest = forms.iter().map(|s| s.2).fold(0.0, f64::max) * TAU / (shortest * f);
        // The means turn by at most 0.02 rad per step: linear
        // interpolation is then within 5·10⁻⁵ of them. Past MOST_NODES
        // they turn faster than the table follows, but then a pixel spans
        // over 590 of the widest wave's cycles and its means are below
        // 8·10⁻⁴ of its amplitude: interpolated, they stay that small,
        // and a thumbnail's table stays a few MB (it grew with the pitch:
        // 180 MB for a 1 px wide image through a spectral stop).
        let step = (0.02 / (0.5 * widest * pitch))
            .min(0.01)
            .max(FRAC_1_SQRT_2 / MOST_NODES as f64);
        let nodes = (FRAC_1_SQRT_2 / step).ceil() as usize + 2;
        let waves = lines
            .iter()
            .map(|line| {
                forms
                    .iter()
                    .map(|&(form, amplitude, radii)| {
                        let k = TAU * radii / (line.lambda * f);
                        let pixel = (0..nodes)
                            .map(|i| {
                                let u = (i as f64 * step).min(FRAC_1_SQRT_2);
                                let v = (1.0 - u * u).sqrt();
                                pixel_mean(pitch, sending, [k * u / TAU, k * v / TAU])
                            })
                            .collect();
                        Wave {
                            form,
                            weights: line.weights(amplitude * line.lambda),
                            pixel,
                        }
                    })
                    .collect()
            })
            .collect();
        // The waves' amplitudes sum to at most 4(Σ√R)² in the units of
        // `discs`, λ f p²/(4π² r³·area) of the light in a pixel.
        let roots: f64 = discs.iter().map(|d| d.radius.sqrt()).sum();
        let longest = lines.iter().map(|l| l.lambda).fold(0.0, f64::max);
        let rims = Rim::find(edges, discs, lines, f, pitch, sending, area);
        let reach = rims.iter().map(|rim| rim.reach).fold(
            libm::cbrt(
                roots * roots * longest * f * pitch * pitch / (PI * PI * area * FRINGE_FLOOR),
            ),
            f64::max,
        );
        Fringes {
            reach,
            rims,
            focal: f,
            radii: discs.iter().map(|d| TAU * d.radius / f).collect(),
            lines: waves,
            inverse_lambda: lines.iter().map(|l| 1.0 / l.lambda).collect(),
            step,
        }
    }

    /// Every wave's pixel mean in the pixels of a row centred at
    /// (`x0` + i·`pitch`, `y`) within `reach` of the centre, into each
    /// plane of `row.sums`, those pixels from `row.start` on.
    pub(super) fn add_row(
        &self,
        x0: f64,
        y: f64,
        pitch: f64,
        planes: usize,
        count: usize,
        row: &mut FringeRow,
    ) {
        let half = (self.reach * self.reach - y * y).max(0.0).sqrt();
        let first = (((-half - x0) / pitch).ceil().max(0.0) as usize).min(count);
        let end = ((((half - x0) / pitch).floor() + 1.0).max(0.0) as usize).clamp(first, count);
        let n = if self.radii.is_empty() {
            0
        } else {
            end - first
        };
        row.start = first;
        row.sums.resize_with(planes, Vec::new);
        for sums in &mut row.sums {
            sums.clear();
            sums.resize(n, 0.0);
        }
        if n == 0 {
            return;
        }
        row.x.clear();
        row.radius.clear();
        row.root.clear();
        row.node.clear();
        row.fraction.clear();
        row.angle.clear();
        for i in first..end {
            let x = x0 + i as f64 * pitch;
            let r = libm::hypot(x, y);
            let t = x.abs().min(y.abs()) / (r * self.step);
            row.radius.push(r);
            row.node.push(t as usize);
            row.fraction.push(t.fract());
            if !self.rims.is_empty() {
                row.x.push(x);
                row.root.push(r.sqrt());
                row.angle.push(libm::atan2(y, x));
            }
        }
        let discs = self.radii.len();
        row.sines.resize_with(discs, Vec::new);
        row.cosines.resize_with(discs, Vec::new);
        row.wave.resize(n, 0.0);
        for (line, (waves, inverse)) in self.lines.iter().zip(&self.inverse_lambda).enumerate() {
            for (j, radius) in self.radii.iter().enumerate() {
                let k = radius * inverse;
                let (sines, cosines) = (&mut row.sines[j], &mut row.cosines[j]);
                sines.resize(n, 0.0);
                cosines.resize(n, 0.0);
                for ((r, s), c) in row
                    .radius
                    .iter()
                    .zip(sines.iter_mut())
                    .zip(cosines.iter_mut())
                {
                    (*s, *c) = sin_cos(k * r);
                }
            }
            for wave in waves {
                let (s, c) = (&row.sines, &row.cosines);
                match wave.form {
                    Waveform::Own(j) => {
                        for ((w, s), c) in row.wave.iter_mut().zip(&s[j]).zip(&c[j]) {
                            *w = -2.0 * s * c;
                        }
                    }
                    Waveform::Sum(j, k) => {
                        let pairs = s[j].iter().zip(&c[j]).zip(s[k].iter().zip(&c[k]));
                        for (w, ((sj, cj), (sk, ck))) in row.wave.iter_mut().zip(pairs) {
                            *w = -(sj * ck + cj * sk);
                        }
                    }
                    Waveform::Difference(j, k) => {
                        let pairs = s[j].iter().zip(&c[j]).zip(s[k].iter().zip(&c[k]));
                        for (w, ((sj, cj), (sk, ck))) in row.wave.iter_mut().zip(pairs) {
                            *w = cj * ck + sj * sk;
                        }
                    }
                }
                for ((value, &node), t) in row.wave.iter_mut().zip(&row.node).zip(&row.fraction) {
                    let (a, b) = (wave.pixel[node], wave.pixel[node + 1]);
                    *value *= a + t * (b - a);
                }
                for (sums, w) in row.sums.iter_mut().zip(&wave.weights) {
                    for (sum, value) in sums.iter_mut().zip(&row.wave) {
                        *sum += w * value;
                    }
                }
            }
            for rim in &self.rims {
                self.add_rim(rim, line, *inverse, y, row);
            }
        }
    }

    /// One rim's beat in one line along the row's pixels within reach:
    /// the waves first, in plain arithmetic that vectorises, then their
    /// pixel means, looked up by angle.
    fn add_rim(&self, rim: &Rim, line: usize, inverse: f64, y: f64, row: &mut FringeRow) {
        let kappa = TAU * inverse / self.focal;
        let [d0, d1] = rim.offset;
        let [n0, n1] = rim.normal;
        let [a0, a1] = rim.along;
        // Across the edge's ray |sinc| ≤ 1/|h|: only the band where the
        // beat can reach the floor, for the nearest pixel of the row.
        let nearest = row.radius.iter().copied().fold(f64::INFINITY, f64::min);
        let width = rim.band / (nearest * nearest * nearest.sqrt());
        let n = row.wave.len();
        let band = match row.x.first() {
            Some(&x0) if n > 1 => band(x0 * a0 + y * a1, (row.x[1] - x0) * a0, width, n),
            _ => 0..n,
        };
        let half = 0.5 * kappa * rim.length;
        row.second.resize(n, 0.0);
        let (sines, cosines) = (
            &row.sines[rim.disc][band.clone()],
            &row.cosines[rim.disc][band.clone()],
        );
        let pixels = row.x[band.clone()]
            .iter()
            .zip(&row.root[band.clone()])
            .zip(sines.iter().zip(cosines));
        let waves = row.wave[band.clone()]
            .iter_mut()
            .zip(row.second[band.clone()].iter_mut());
        for ((first, second), ((x, root), (sz, cz))) in waves.zip(pixels) {
            let (sd, cd) = sin_cos(kappa * (x * d0 + y * d1));
            let h = half * (x * a0 + y * a1);
            let sinc = if h.abs() < 1e-8 {
                1.0
            } else {
                sin_cos(h).0 / h
            };
            let amplitude = sinc * (x * n0 + y * n1) / root;
            // sin and cos of z − 3π/4.
            let (sa, ca) = (-(sz + cz) * FRAC_1_SQRT_2, (sz - cz) * FRAC_1_SQRT_2);
            *first = amplitude * (sa * cd + ca * sd);
            *second = amplitude * (sa * cd - ca * sd);
        }
        let pixel = &rim.pixel[line];
        let waves = row.wave[band.clone()]
            .iter_mut()
            .zip(&row.second[band.clone()]);
        for ((first, second), theta) in waves.zip(&row.angle[band.clone()]) {
            let t = (theta + PI) / rim.step;
            let (node, frac) = (t as usize, t.fract());
            let p1 = pixel[node] + frac * (pixel[node + 1] - pixel[node]);
            let node = node + rim.half_turn;
            let p2 = pixel[node] + frac * (pixel[node + 1] - pixel[node]);
            *first = p1 * *first - p2 * second;
        }
        for (sums, w) in row.sums.iter_mut().zip(&rim.weights[line]) {
            for (sum, value) in sums[band.clone()].iter_mut().zip(&row.wave[band.clone()]) {
                *sum += w * value;
            }
        }
    }

    /// A row's fringes in pixel `i` and `plane`.
    pub(super) fn at(row: &FringeRow, i: usize, plane: usize) -> f64 {
        i.checked_sub(row.start)
            .and_then(|k| row.sums[plane].get(k))
            .copied()
            .unwrap_or(0.0)
    }
}
