//! A distant source's ghosts on the sensor, rasterised from a bundle of
//! real rays (Hullin et al., SIGGRAPH 2011): a grid of rays over the
//! entrance pupil is traced along a path; each cell of four neighbouring
//! rays that all arrive carries the light of its patch of the pupil,
//! times the mean of their weights, spread evenly over the quadrilateral
//! they land on, so that the irradiance follows the bundle's compression
//! and stretching (docs/physics.md §12). The light is in units of what
//! the direct path brings to the source's own image: a ghost's pixels
//! sum to its path's power over the image's.

use std::borrow::Cow;

use super::bundle::{draw_bundle, follow, Bundle, BundleRays, GRID};
use super::canvas::{Canvas, Patch};
use super::passage::{coarse, found, front, search, Square};
use super::trace::{Arrival, Layout, Path, Route, Vector};
use crate::control::Cancel;

/// A sensor of `width`×`height` pixels of `pitch_mm`, the optical axis
/// through `centre` (the display window's centre: a frame's overscan lies
/// beyond it); rows run downwards, the image's y upwards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensor {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// The pixel pitch, mm.
    pub pitch_mm: f64,
    /// Where the axis meets it: (column, row), pixel i spanning [i, i + 1).
    pub centre: (f64, f64),
}

impl Sensor {
    /// A sensor of `width`×`height` pixels of `pitch_mm`, the axis through
    /// its centre.
    pub fn centred(width: usize, height: usize, pitch_mm: f64) -> Sensor {
        Sensor {
            width,
            height,
            pitch_mm,
            centre: (0.5 * width as f64, 0.5 * height as f64),
        }
    }

    /// (column, row) in pixels of a point of the image plane (mm), pixel
    /// i spanning [i, i + 1).
    pub(crate) fn pixel(&self, at: Vector) -> (f64, f64) {
        (
            self.centre.0 + at[0] / self.pitch_mm,
            self.centre.1 - at[1] / self.pitch_mm,
        )
    }
}

/// The light the direct path brings to the image from a source in
/// direction `field`, per unit of its irradiance: what a ghost's light is
/// counted against.
pub fn direct_light(layout: &Layout, field: Vector, nm: f64) -> f64 {
    direct_light_in(layout, field, nm, front(layout, field, nm))
}

/// As [`direct_light`], its light passing the pupil within `square`
/// ([`front`]).
fn direct_light_in(layout: &Layout, field: Vector, nm: f64, square: Option<Square>) -> f64 {
    let route = layout.route(Path::Direct, nm);
    let Some(square) = square else {
        return 0.0;
    };
    Bundle::new(layout, route, field, square).light()
}

/// Adds to `plane` (the sensor's pixels, rows downwards) the ghost of
/// `path` of a source in direction `field` at `nm`, scaled by `scale`
/// over `direct` (the [`direct_light`] of that source): the pixels gain
/// `scale` × the ghost's light / the image's. Returns the light added
/// (including what falls outside the sensor, which is dropped).
pub fn add_ghost(
    layout: &Layout,
    path: Path,
    (field, nm): (Vector, f64),
    (direct, scale): (f64, f64),
    sensor: &Sensor,
    plane: &mut [f64],
) -> f64 {
    let square = if layout.stop_first(path) {
        front(layout, field, nm)
    } else {
        search(layout, &layout.route(path, nm), field)
    };
    // Never cancelled: the one drawing is always there.
    let never = Cancel::new();
    let drawing = (sensor, &never);
    let patch = draw(
        layout,
        (&[path], square),
        (field, &[nm]),
        (direct, scale),
        drawing,
    )
    .ok()
    .and_then(|mut paths| paths.pop()?.pop())
    .unwrap_or_default();
    let mut canvas = Canvas::new(*sensor, 1);
    canvas.add(&patch, 0, 1.0);
    for (p, v) in plane.iter_mut().zip(&canvas.finish()[0]) {
        *p += v;
    }
    patch.light
}

/// As [`add_ghost`] for each of `paths` at each of the wavelengths
/// `nms`: each bundle drawn as it is traced ([`follow`]).
fn draw(
    layout: &Layout,
    (paths, square): (&[Path], Option<Square>),
    (field, nms): (Vector, &[f64]),
    (direct, scale): (f64, f64),
    (sensor, cancel): (&Sensor, &Cancel),
) -> crate::Result<Vec<Vec<Patch>>> {
    let Some(square) = square else {
        return Ok(vec![vec![Patch::default(); nms.len()]; paths.len()]);
    };
    let each = |bundle: Bundle| draw_bundle(&bundle, (direct, scale), sensor);
    follow(layout, (paths, square), (field, nms), cancel, &each)
}

/// The unit direction of a distant source `x` degrees right of the axis
/// and `y` degrees above it (as seen through the lens: tan x and tan y
/// its image's offsets over the focal length), +z into the lens.
pub fn direction(x: f64, y: f64) -> Vector {
    towards((libm::tan(x.to_radians()), libm::tan(y.to_radians())))
}

/// The unit direction whose tangents right of the axis and above it are
/// (tx, ty), +z into the lens.
pub(crate) fn towards((tx, ty): (f64, f64)) -> Vector {
    let norm = (tx * tx + ty * ty + 1.0).sqrt();
    [tx / norm, ty / norm, 1.0 / norm]
}

/// The light a ghost is traced in: three wavelengths, each channel's
/// sensitivity-weighted mean (R, G, B), or 17 from 380 to 780 nm, each
/// with its weight in R, G and B (the spectral apertures' light,
/// docs/physics.md §6).
pub fn light(spectral: bool) -> Vec<(f64, Vec<f64>)> {
    use crate::optics::aperture::spectrum;
    if spectral {
        spectrum::Light::Spectral.wavelengths()
    } else {
        spectrum::mean_wavelengths()
            .iter()
            .enumerate()
            .map(|(c, &nm)| {
                let mut weights = vec![0.0; 3];
                weights[c] = 1.0;
                (nm, weights)
            })
            .collect()
    }
}

/// A source's ghosts on a sensor.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// One plane per channel of the light, rows downwards: each pixel the
    /// light it receives over the light of the source's own image in that
    /// channel (a source of even spectral power: white light).
    pub planes: Vec<Vec<f64>>,
    /// Each channel's ghost light over its image's, including what falls
    /// beyond the sensor.
    pub light: Vec<f64>,
    /// Each path's light over the image's (the channels' mean), the
    /// brightest first.
    pub ranked: Vec<(Path, f64)>,
}

/// Every ghost of a distant source in direction `field`, on `sensor`, in
/// `light` (its wavelengths, each with its weight in every channel, as
/// [`light`] gives): [`trace`], painted at the source's brightness.
pub fn render(
    layout: &Layout,
    field: Vector,
    sensor: &Sensor,
    light: &[(f64, Vec<f64>)],
    control: &mut crate::control::Control,
) -> crate::Result<Rendered> {
    let traced = trace(layout, field, sensor, light, control)?;
    let channels = traced.light.len();
    let mut canvas = Canvas::new(*sensor, channels);
    let identity: Vec<Vec<f64>> = (0..channels)
        .map(|t| (0..channels).map(|c| f64::from(u8::from(t == c))).collect())
        .collect();
    traced.paint(&mut canvas, &identity);
    Ok(Rendered {
        planes: canvas.finish(),
        light: traced.light,
        ranked: traced.ranked,
    })
}

/// A source's ghosts traced, each path's at each wavelength drawn at the
/// light of an image of 1 in each channel, to be painted at the source's
/// own.
#[derive(Debug, Clone)]
pub struct Traced {
    /// (wavelength, its ghost of each path), in the order traced.
    patches: Vec<(usize, Patch)>,
    /// For each wavelength, its share of each channel's image.
    shares: Vec<Vec<f64>>,
    /// Each channel's ghost light over its image's, including what falls
    /// beyond the sensor.
    pub light: Vec<f64>,
    /// Each path's light over the image's (the channels' mean), the
    /// brightest first.
    pub ranked: Vec<(Path, f64)>,
}

impl Traced {
    /// Adds the ghosts to `canvas`: its plane t gets Σ_c mix[t][c] ×
    /// channel c's ghosts (each pixel its light over channel c's image).
    pub fn paint(&self, canvas: &mut Canvas, mix: &[Vec<f64>]) {
        for (k, patch) in &self.patches {
            for (target, row) in mix.iter().enumerate() {
                let scale: f64 = row.iter().zip(&self.shares[*k]).map(|(m, s)| m * s).sum();
                canvas.add(patch, target, scale);
            }
        }
    }
}

/// Every ghost of a distant source in direction `field`, on `sensor`, in
/// `light` ([`Rays::trace_drawn`], the rays not kept).
pub fn trace(
    layout: &Layout,
    field: Vector,
    sensor: &Sensor,
    light: &[(f64, Vec<f64>)],
    control: &mut crate::control::Control,
) -> crate::Result<Traced> {
    let cancel = control.cancel();
    let (traced, _) = Rays::trace_drawn(layout, field, (sensor, light), false, &cancel)?;
    control.report(1.0);
    Ok(traced)
}

/// The direct path's bundle at one wavelength: where its light enters the
/// pupil, and its rays; `None` where none does.
type Direct = Option<(Square, BundleRays)>;

/// Where a path's light passes the pupil and, per wavelength, what was
/// made of its bundle; `None` where none passes.
type PerPath<T> = Option<(Square, Vec<T>)>;

/// Every ray a distant source's ghosts are drawn from, traced through the
/// lens but not clipped by the stop's opening, which the cells clip
/// between them: the same rays draw the ghosts of any stop of the same
/// circle (other blades, rotation or roundness at the same f-number), so
/// a front end that keeps them redraws the ghosts without tracing.
#[derive(Debug, Clone)]
pub struct Rays {
    /// The source's direction.
    pub field: Vector,
    /// The wavelengths traced.
    nms: Vec<f64>,
    /// Per wavelength, the direct path's bundle: where its light enters
    /// the pupil, and its rays.
    directs: Vec<Direct>,
    /// Per path of [`Layout::ghosts`], where its light passes the pupil
    /// and, per wavelength, its bundle's rays.
    paths: Vec<PerPath<BundleRays>>,
}

impl Rays {
    /// Every ghost of a distant source in direction `field`, on `sensor`,
    /// in `light`, each bundle drawn as it is traced, and with `keep` its
    /// rays too. The paths are traced in parallel and kept in their order:
    /// the same bits on any number of threads. Each part hears `cancel`
    /// before it starts.
    pub fn trace_drawn(
        layout: &Layout,
        field: Vector,
        (sensor, light): (&Sensor, &[(f64, Vec<f64>)]),
        keep: bool,
        cancel: &Cancel,
    ) -> crate::Result<(Traced, Option<Rays>)> {
        let nms: Vec<f64> = light.iter().map(|l| l.0).collect();
        let each = |bundle: Bundle| {
            let patch = draw_bundle(&bundle, (1.0, 1.0), sensor);
            (patch, keep.then(|| bundle.rays.into_owned()))
        };
        let (directs, by_path) = follow_all(layout, field, &nms, cancel, &each)?;
        let mut drawn = Vec::with_capacity(by_path.len() * nms.len());
        let mut paths = Vec::with_capacity(by_path.len());
        for path in by_path {
            match path {
                Some((square, by_nm)) => {
                    let (patches, rays): (Vec<Patch>, Vec<Option<BundleRays>>) =
                        by_nm.into_iter().unzip();
                    drawn.extend(patches);
                    let rays: Option<Vec<BundleRays>> = rays.into_iter().collect();
                    paths.push(rays.map(|rays| (square, rays)));
                }
                None => {
                    drawn.extend((0..nms.len()).map(|_| Patch::default()));
                    paths.push(None);
                }
            }
        }
        let traced = assemble(layout, (field, light), &directs, drawn, cancel)?;
        let rays = keep.then_some(Rays {
            field,
            nms,
            directs,
            paths,
        });
        Ok((traced, rays))
    }

    /// Whether these are the rays of a source in direction `field` at the
    /// wavelengths of `light`.
    pub fn are_for(&self, field: Vector, light: &[(f64, Vec<f64>)]) -> bool {
        self.field == field && self.nms.iter().eq(light.iter().map(|l| &l.0))
    }

    /// The bytes they hold.
    pub fn bytes(&self) -> u64 {
        let bundle = (GRID + 1) * (GRID + 1) * std::mem::size_of::<Option<Arrival>>();
        let bundles = self.directs.iter().flatten().count()
            + self
                .paths
                .iter()
                .flatten()
                .map(|(_, by_nm)| by_nm.len())
                .sum::<usize>();
        (bundles * bundle) as u64
    }

    /// The ghosts these rays draw through `layout` (the lens they were
    /// traced through, its stop's opening any within the same circle) on
    /// `sensor`, in `light` (the wavelengths they were traced at): each
    /// path's at each wavelength drawn at the light of an image of 1 in
    /// each channel.
    pub fn draw(
        &self,
        layout: &Layout,
        sensor: &Sensor,
        light: &[(f64, Vec<f64>)],
        cancel: &Cancel,
    ) -> crate::Result<Traced> {
        use rayon::prelude::*;
        let paths = layout.ghosts();
        let nms = self.nms.len();
        // Every path's bundle at every wavelength, drawn side by side and
        // kept in order (path, then wavelength).
        let drawn: Vec<Patch> = (0..paths.len() * nms)
            .into_par_iter()
            .map(|at| {
                let (p, k) = (at / nms, at % nms);
                self.paths[p]
                    .as_ref()
                    .map_or_else(Patch::default, |(square, by_nm)| {
                        let bundle = Bundle {
                            layout,
                            route: layout.route(paths[p], self.nms[k]),
                            field: self.field,
                            square: *square,
                            rays: Cow::Borrowed(&by_nm[k]),
                        };
                        draw_bundle(&bundle, (1.0, 1.0), sensor)
                    })
            })
            .collect();
        cancel.check()?;
        assemble(layout, (self.field, light), &self.directs, drawn, cancel)
    }
}

/// `each` of every ghost's bundle of a distant source in direction
/// `field`, at the wavelengths `nms` (per path of [`Layout::ghosts`], in
/// order), and the direct path's bundle at each wavelength.
fn follow_all<T: Send>(
    layout: &Layout,
    field: Vector,
    nms: &[f64],
    cancel: &Cancel,
    each: &(impl Fn(Bundle) -> T + Sync),
) -> crate::Result<(Vec<Direct>, Vec<PerPath<T>>)> {
    use rayon::prelude::*;
    let paths = layout.ghosts();
    // Where the light that meets the stop first enters the pupil, at each
    // wavelength: the direct path's and most ghosts' ([`front`]).
    let fronts: Vec<Option<Square>> = nms.par_iter().map(|&nm| front(layout, field, nm)).collect();
    let directs = nms
        .par_iter()
        .zip(&fronts)
        .map(|(&nm, square)| {
            square.map(|square| {
                let route = layout.route(Path::Direct, nm);
                let bundle = Bundle::new(layout, route, field, square);
                (square, bundle.rays.into_owned())
            })
        })
        .collect();
    // Where each path's light passes the pupil, at every wavelength. A path
    // that meets the stop first passes within where the direct path's
    // light reaches it. The others are looked for at the middle
    // wavelength: the bundle's square is a coarse cell wider than their
    // light each way, which the dispersion's shifts stay within.
    let middle = nms.get(nms.len() / 2).copied().unwrap_or(550.0);
    let front = Square::cover(fronts);
    let (first, others): (Vec<usize>, Vec<usize>) =
        (0..paths.len()).partition(|&p| layout.stop_first(paths[p]));
    let entrance = Square::entrance(layout, field);
    let routes: Vec<Route> = others
        .iter()
        .map(|&p| layout.route(paths[p], middle))
        .collect();
    let searched = layout.follow_unclipped_routes(&routes, &coarse(layout, field, entrance));
    cancel.check()?;
    // The paths that meet the stop first together, sharing their way in;
    // then every other on its own; kept in the paths' order.
    let group: Vec<Path> = first.iter().map(|&p| paths[p]).collect();
    let together: Vec<PerPath<T>> = match front {
        Some(square) => follow(layout, (&group, square), (field, nms), cancel, each)?
            .into_iter()
            .map(|done| Some((square, done)))
            .collect(),
        None => group.iter().map(|_| None).collect(),
    };
    let alone: Vec<PerPath<T>> = others
        .par_iter()
        .zip(&searched)
        .map(|(&p, rays)| {
            cancel.check()?;
            let Some(square) = found(layout, entrance, rays) else {
                return Ok(None);
            };
            let one = follow(layout, (&paths[p..=p], square), (field, nms), cancel, each)?;
            Ok(one.into_iter().next().map(|done| (square, done)))
        })
        .collect::<crate::Result<_>>()?;
    let mut by_path: Vec<PerPath<T>> = paths.iter().map(|_| None).collect();
    for (p, done) in first
        .into_iter()
        .zip(together)
        .chain(others.into_iter().zip(alone))
    {
        by_path[p] = done;
    }
    Ok((directs, by_path))
}

/// A source's ghosts from their patches (`drawn`, path then wavelength,
/// each at the light of an image of 1) and the direct path's bundles
/// through `layout`'s stop: each wavelength's share of each channel's
/// image, each channel's ghost light, the paths ranked.
fn assemble(
    layout: &Layout,
    (field, light): (Vector, &[(f64, Vec<f64>)]),
    direct_bundles: &[Direct],
    mut drawn: Vec<Patch>,
    cancel: &Cancel,
) -> crate::Result<Traced> {
    use rayon::prelude::*;
    let paths = layout.ghosts();
    let channels = light.first().map_or(0, |(_, w)| w.len());
    let nms = light.len();
    // Each channel's image: its weights times the direct path's light.
    let directs: Vec<f64> = direct_bundles
        .par_iter()
        .zip(light)
        .map(|(direct, (nm, _))| {
            direct.as_ref().map_or(0.0, |(square, rays)| {
                let bundle = Bundle {
                    layout,
                    route: layout.route(Path::Direct, *nm),
                    field,
                    square: *square,
                    rays: Cow::Borrowed(rays),
                };
                bundle.light()
            })
        })
        .collect();
    cancel.check()?;
    let images: Vec<f64> = (0..channels)
        .map(|c| light.iter().zip(&directs).map(|((_, w), d)| w[c] * d).sum())
        .collect();
    let shares: Vec<Vec<f64>> = light
        .iter()
        .map(|(_, weights)| {
            (0..channels)
                .map(|c| {
                    if images[c] > 0.0 {
                        weights[c] / images[c]
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let mut patches = Vec::new();
    let mut ranked = vec![0.0; paths.len()];
    let mut totals = vec![0.0; channels];
    for k in (0..nms).filter(|&k| directs[k] > 0.0) {
        for (p, ranked) in ranked.iter_mut().enumerate() {
            let patch = std::mem::take(&mut drawn[p * nms + k]);
            for (channel, share) in shares[k].iter().enumerate() {
                *ranked += share * patch.light / channels as f64;
                totals[channel] += share * patch.light;
            }
            patches.push((k, patch));
        }
    }
    let mut ranked: Vec<(Path, f64)> = paths.into_iter().zip(ranked).collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
    Ok(Traced {
        patches,
        shares,
        light: totals,
        ranked,
    })
}
