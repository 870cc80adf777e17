//! Where a path's light passes the entrance pupil, looked for before its
//! bundle is traced (docs/physics.md §12): coarse grids of rays traced
//! without clipping, and the square about the cells between whose rays
//! light may pass, laid along the source's azimuth.

use super::trace::{Arrival, Layout, Path, Ray, Route, Vector};

/// Cells across the whole entrance (the first surface's clear aperture
/// as the source sees it), where each path's light is first looked for.
const COARSE: usize = 32;

/// A square of the entrance pupil's plane, in units of the pupil's
/// radius, its sides along and across the source's azimuth, centred on
/// the line through the axis towards the source: the lens is round, so a
/// bundle drawn over it is as symmetric about that line as the light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Square {
    /// Its centre's distance from the axis along the azimuth.
    along: f64,
    /// Half its side.
    pub(super) half: f64,
    /// The azimuth's cosine and sine.
    axis: (f64, f64),
}

impl Square {
    /// The point at grid position (i, j) of `cells` across, fractional
    /// within a cell: along and across the azimuth.
    pub(super) fn local(&self, cells: usize, i: f64, j: f64) -> (f64, f64) {
        let step = 2.0 * self.half / cells as f64;
        (self.along - self.half + i * step, -self.half + j * step)
    }

    /// The pupil point at grid position (i, j) of `cells` across.
    pub(super) fn point(&self, cells: usize, i: f64, j: f64) -> (f64, f64) {
        let (u, v) = self.local(cells, i, j);
        let (c, s) = self.axis;
        (u * c - v * s, u * s + v * c)
    }

    /// The rays from direction `field` at every `stride`-th position each
    /// way of a grid of `cells` across, rows of constant pupil y.
    pub(super) fn rays(
        &self,
        layout: &Layout,
        field: Vector,
        cells: usize,
        stride: usize,
    ) -> Vec<Ray> {
        let side = cells / stride + 1;
        (0..side * side)
            .map(|k| {
                let (i, j) = (stride * (k % side), stride * (k / side));
                layout.collimated(field, self.point(cells, i as f64, j as f64))
            })
            .collect()
    }

    /// The least square on the line about the box from `lo` to `hi`
    /// (along and across the azimuth).
    fn about(lo: (f64, f64), hi: (f64, f64), axis: (f64, f64)) -> Square {
        Square {
            along: 0.5 * (lo.0 + hi.0),
            half: (0.5 * (hi.0 - lo.0)).max(lo.1.abs()).max(hi.1.abs()),
            axis,
        }
    }

    /// The least square about every one of `squares` that is some.
    pub(super) fn cover(squares: impl IntoIterator<Item = Option<Square>>) -> Option<Square> {
        let mut squares = squares.into_iter().flatten().peekable();
        let axis = squares.peek()?.axis;
        let (lo, hi) = squares.fold(
            (
                (f64::INFINITY, f64::INFINITY),
                (f64::NEG_INFINITY, f64::NEG_INFINITY),
            ),
            |(lo, hi), q| {
                (
                    (lo.0.min(q.along - q.half), lo.1.min(-q.half)),
                    (hi.0.max(q.along + q.half), hi.1.max(q.half)),
                )
            },
        );
        Some(Square::about(lo, hi, axis))
    }

    /// The square every ray that enters the lens from direction `field`
    /// comes through: the first surface's clear aperture, seen from the
    /// entrance pupil's plane along the field.
    pub(super) fn entrance(layout: &Layout, field: Vector) -> Square {
        let (z_pupil, radius) = layout.pupil;
        let (z_first, semi) = layout.entrance();
        let back = (z_pupil - z_first) / field[2];
        let off = libm::hypot(field[0], field[1]);
        Square {
            along: back * off / radius,
            half: semi / radius,
            axis: if off > 0.0 {
                (field[0] / off, field[1] / off)
            } else {
                (1.0, 0.0)
            },
        }
    }
}

/// Where in the pupil the light of `route` passes, looked for on a coarse
/// grid over the whole entrance: the square about the cells whose rays
/// may pass between them ([`may_pass`]), a coarse cell wider each way;
/// `None` where no light passes.
pub fn search(layout: &Layout, route: &Route, field: Vector) -> Option<Square> {
    search_in(layout, route, field, Square::entrance(layout, field))
}

/// Where the light that meets the stop before any reflection enters the
/// pupil at `nm` (every path's, when [`Layout::stop_first`]): looked for
/// along the surfaces up to the stop, over the whole entrance and then
/// again over what that found, so the square is a fine cell wider than
/// the light each way rather than a coarse one.
pub fn front(layout: &Layout, field: Vector, nm: f64) -> Option<Square> {
    let route = layout.route(Path::Direct, nm).to_stop();
    let coarse = search(layout, &route, field)?;
    search_in(layout, &route, field, coarse)
}

/// As [`search`], over the square `within` of the pupil.
pub(super) fn search_in(
    layout: &Layout,
    route: &Route,
    field: Vector,
    within: Square,
) -> Option<Square> {
    let rays = layout.follow_unclipped_all(route, &coarse(layout, field, within));
    found(layout, within, &rays)
}

/// The rays of a search over `within` from direction `field`.
pub(super) fn coarse(layout: &Layout, field: Vector, within: Square) -> Vec<Ray> {
    within.rays(layout, field, COARSE, 1)
}

/// Where a search over `within` found the light, from its `rays`.
pub(super) fn found(layout: &Layout, within: Square, rays: &[Option<Arrival>]) -> Option<Square> {
    let side = COARSE + 1;
    let (mut lo, mut hi) = ((usize::MAX, usize::MAX), (0, 0));
    for j in 0..COARSE {
        for i in 0..COARSE {
            let corners =
                [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(di, dj)| rays[(j + dj) * side + i + di]);
            if may_pass(layout, &corners) {
                lo = (lo.0.min(i), lo.1.min(j));
                hi = (hi.0.max(i + 1), hi.1.max(j + 1));
            }
        }
    }
    if lo.0 > hi.0 {
        return None;
    }
    let step = 2.0 * within.half / COARSE as f64;
    let mut square = Square::about(
        within.local(COARSE, lo.0 as f64 - 1.0, lo.1 as f64 - 1.0),
        within.local(COARSE, hi.0 as f64 + 1.0, hi.1 as f64 + 1.0),
        within.axis,
    );
    square.half = square.half.max(step);
    Some(square)
}

/// Whether light may pass between the rays of a cell's corners that
/// arrive: their margins within the apertures, stretched by a quarter of
/// their spread, reach 0, and at each of the path's crossings of the
/// stop's plane the box of their crossings, a quarter wider, meets the
/// circle about the opening.
pub(super) fn may_pass(layout: &Layout, corners: &[Option<Arrival>; 4]) -> bool {
    let alive = || corners.iter().flatten();
    let Some(first) = alive().next() else {
        return false;
    };
    let (low, high) = alive().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), a| {
        (l.min(a.margin), h.max(a.margin))
    });
    if high + 0.25 * (high - low) < 0.0 {
        return false;
    }
    let radius = layout.opening;
    (0..first.stop.points().len()).all(|k| {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for a in alive() {
            let p = a.stop.points()[k];
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        let grow = [0.125 * (hi[0] - lo[0]), 0.125 * (hi[1] - lo[1])];
        let nearest = [
            0.0f64.clamp(lo[0] - grow[0], hi[0] + grow[0]),
            0.0f64.clamp(lo[1] - grow[1], hi[1] + grow[1]),
        ];
        nearest[0] * nearest[0] + nearest[1] * nearest[1] <= radius * radius
    })
}
