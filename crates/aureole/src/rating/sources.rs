//! Finding glare sources: the pixels above a threshold, joined into one
//! source wherever two of them lie within a given angle of each other,
//! which is the grouping evalglare's scans converge to (single linkage).
//!
//! evalglare compares each source pixel with every pixel within the
//! search radius, again and again until nothing changes. Here the pixels
//! are runs along rows: runs that touch (8-connected) are one source at
//! once, and only the pixels on the rim of a region can lie within the
//! angle of another region (a cap about a pixel outside a region that
//! reaches into it crosses its rim), so only rim pixels are compared,
//! through a grid of cells one chord of the angle wide on the unit sphere.

use std::collections::HashMap;

use crate::control::Cancel;
use crate::error::Result;
use crate::view::Pixels;

/// Pixels `start..end` of one row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Run {
    /// The row, from the top.
    pub row: u32,
    /// The first column.
    pub start: u32,
    /// One past the last column.
    pub end: u32,
}

/// Sets of runs joined by union; the lowest index is a set's root, so the
/// sets come out the same whatever order the joins came in.
struct Sets(Vec<u32>);

impl Sets {
    fn new(n: usize) -> Sets {
        Sets((0..n as u32).collect())
    }

    fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let up = self.0[self.0[i as usize] as usize];
            self.0[i as usize] = up;
            i = up;
        }
        i
    }

    fn join(&mut self, a: u32, b: u32) -> bool {
        let (a, b) = (self.find(a), self.find(b));
        if a == b {
            return false;
        }
        let (low, high) = (a.min(b), a.max(b));
        self.0[high as usize] = low;
        true
    }
}

/// The runs of pixels for which `keep(column, row)` holds, row by row.
pub fn runs(
    width: usize,
    height: usize,
    keep: impl Fn(usize, usize) -> bool + Sync,
    cancel: &Cancel,
) -> Result<Vec<Run>> {
    use rayon::prelude::*;
    let rows: Vec<Vec<Run>> = (0..height)
        .into_par_iter()
        .map(|row| {
            let mut found = Vec::new();
            let mut start = None;
            for column in 0..=width {
                let inside = column < width && keep(column, row);
                match (inside, start) {
                    (true, None) => start = Some(column),
                    (false, Some(s)) => {
                        found.push(Run {
                            row: row as u32,
                            start: s as u32,
                            end: column as u32,
                        });
                        start = None;
                    }
                    _ => {}
                }
            }
            found
        })
        .collect();
    cancel.check()?;
    Ok(rows.into_iter().flatten().collect())
}

/// The pixels of `runs` for which `keep(column, row)` holds, as runs in
/// the same order: a subset found without looking at the rest of the
/// picture.
pub fn within(runs: &[Run], keep: impl Fn(usize, usize) -> bool) -> Vec<Run> {
    let mut found = Vec::new();
    for run in runs {
        let mut start = None;
        for column in run.start..=run.end {
            let inside = column < run.end && keep(column as usize, run.row as usize);
            match (inside, start) {
                (true, None) => start = Some(column),
                (false, Some(s)) => {
                    found.push(Run {
                        row: run.row,
                        start: s,
                        end: column,
                    });
                    start = None;
                }
                _ => {}
            }
        }
    }
    found
}

/// Where each row's runs begin in `runs` (sorted by row): `rows[r]..rows[r + 1]`.
fn row_index(runs: &[Run], height: usize) -> Vec<usize> {
    let mut first = vec![runs.len(); height + 1];
    for (i, run) in runs.iter().enumerate().rev() {
        first[run.row as usize] = i;
    }
    for r in (0..height).rev() {
        first[r] = first[r].min(first[r + 1]);
    }
    first
}

/// Whether `column` lies in one of `runs` (one row's, sorted), from the
/// cursor on; the cursor moves past runs that end before it.
fn covered(runs: &[Run], cursor: &mut usize, column: u32) -> bool {
    while *cursor < runs.len() && runs[*cursor].end <= column {
        *cursor += 1;
    }
    runs.get(*cursor).is_some_and(|r| r.start <= column)
}

/// Groups `runs` (sorted by row and column) into sources: touching runs,
/// and runs with pixels within `angle` radians of each other. Returns each
/// run's group, numbered 0.. in the order of their first runs.
pub fn group(
    runs: &[Run],
    height: usize,
    pixels: &Pixels,
    angle: f64,
    cancel: &Cancel,
) -> Result<Vec<u32>> {
    let mut sets = Sets::new(runs.len());
    let rows = row_index(runs, height);
    for r in 1..height {
        let (above, here) = (&runs[rows[r - 1]..rows[r]], rows[r]..rows[r + 1]);
        let mut a = 0;
        for i in here {
            let run = runs[i];
            while a < above.len() && above[a].end < run.start {
                a += 1;
            }
            let mut b = a;
            while b < above.len() && above[b].start <= run.end {
                sets.join(i as u32, (rows[r - 1] + b) as u32);
                b += 1;
            }
        }
    }
    cancel.check()?;
    join_within(runs, &rows, height, pixels, angle, &mut sets, cancel)?;
    let mut number = HashMap::new();
    Ok((0..runs.len() as u32)
        .map(|i| {
            let root = sets.find(i);
            let next = number.len() as u32;
            *number.entry(root).or_insert(next)
        })
        .collect())
}

/// Joins the sets of runs with rim pixels within `angle` of each other.
fn join_within(
    runs: &[Run],
    rows: &[usize],
    height: usize,
    pixels: &Pixels,
    angle: f64,
    sets: &mut Sets,
    cancel: &Cancel,
) -> Result<()> {
    let chord = 2.0 * libm::sin(angle / 2.0);
    let near = libm::cos(angle);
    if chord.is_nan() || chord <= 0.0 {
        return Ok(());
    }
    // Each cell of the grid holds its rim pixels: (set, direction).
    let mut cells: HashMap<[i32; 3], Vec<(u32, [f64; 3])>> = HashMap::new();
    for r in 0..height {
        let here = &runs[rows[r]..rows[r + 1]];
        let above = if r > 0 {
            &runs[rows[r - 1]..rows[r]]
        } else {
            &[]
        };
        let below = runs
            .get(rows[r + 1]..rows[(r + 2).min(height)])
            .unwrap_or(&[]);
        let (mut ca, mut cb) = (0, 0);
        for (k, run) in here.iter().enumerate() {
            let set = sets.find((rows[r] + k) as u32);
            for column in run.start..run.end {
                let inner = column > run.start
                    && column + 1 < run.end
                    && covered(above, &mut ca, column)
                    && covered(below, &mut cb, column);
                if inner {
                    continue;
                }
                let Some(sight) = pixels.pixel(column as usize, r) else {
                    continue;
                };
                let d = sight.direction;
                let key = d.map(|c| libm::floor(c / chord) as i32);
                cells.entry(key).or_default().push((set, d));
            }
        }
        if r % 256 == 0 {
            cancel.check()?;
        }
    }
    let mut keys: Vec<[i32; 3]> = cells.keys().copied().collect();
    keys.sort_unstable();
    // Within a cell, the pixels of one set together.
    for points in cells.values_mut() {
        points.sort_by_key(|(set, _)| *set);
    }
    let slices = |points: &[(u32, [f64; 3])]| -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut start = 0;
        for i in 1..=points.len() {
            if i == points.len() || points[i].0 != points[start].0 {
                out.push((start, i));
                start = i;
            }
        }
        out
    };
    for (n, key) in keys.iter().enumerate() {
        let here = &cells[key];
        let here_slices = slices(here);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let other_key = [key[0] + dx, key[1] + dy, key[2] + dz];
                    if other_key < *key {
                        continue;
                    }
                    let Some(other) = cells.get(&other_key) else {
                        continue;
                    };
                    let other_slices = slices(other);
                    for (i, &(a0, a1)) in here_slices.iter().enumerate() {
                        for (j, &(b0, b1)) in other_slices.iter().enumerate() {
                            if other_key == *key && j <= i {
                                continue;
                            }
                            if sets.find(here[a0].0) == sets.find(other[b0].0) {
                                continue;
                            }
                            let close = here[a0..a1].iter().any(|(_, p)| {
                                other[b0..b1]
                                    .iter()
                                    .any(|(_, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2] >= near)
                            });
                            if close {
                                sets.join(here[a0].0, other[b0].0);
                            }
                        }
                    }
                }
            }
        }
        if n % 1024 == 0 {
            cancel.check()?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::{Projection, View};

    fn find(mask: &[&str], pixels: &Pixels, angle: f64) -> (Vec<Run>, Vec<u32>) {
        let width = mask[0].len();
        let runs = runs(
            width,
            mask.len(),
            |c, r| mask[r].as_bytes()[c] == b'#',
            &Cancel::new(),
        )
        .unwrap();
        let groups = group(&runs, mask.len(), pixels, angle, &Cancel::new()).unwrap();
        (runs, groups)
    }

    #[test]
    fn touching_pixels_are_one_source_and_far_ones_two() {
        let mask = ["#.........", ".#......##", "..#.......", ".........."];
        // 1° a pixel, sources joined within 0.5°: only touching runs join.
        let pixels = View::new(Projection::Equidistant, 10.0).pixels(10, 4);
        let (runs, groups) = find(&mask, &pixels, 0.5f64.to_radians());
        assert_eq!(runs.len(), 4);
        assert_eq!(groups, vec![0, 0, 1, 0]);
    }

    #[test]
    fn sources_within_the_angle_join_across_a_gap() {
        let mask = ["##....##..........##"];
        let pixels = View::new(Projection::Equidistant, 20.0).pixels(20, 1);
        // Nearest pixels 5° and 11° apart: joined within 5.5°, the far
        // one apart.
        let (_, groups) = find(&mask, &pixels, 5.5f64.to_radians());
        assert_eq!(groups, vec![0, 0, 1]);
        let (_, groups) = find(&mask, &pixels, 4.5f64.to_radians());
        assert_eq!(groups, vec![0, 1, 2]);
        let (_, groups) = find(&mask, &pixels, 11.5f64.to_radians());
        assert_eq!(groups, vec![0, 0, 0]);
    }

    #[test]
    fn the_pixels_within_runs_are_found_among_them_alone() {
        let mask = ["##.####", ".###..#"];
        let pixels = View::new(Projection::Equidistant, 7.0).pixels(7, 2);
        let (runs, _) = find(&mask, &pixels, 0.1f64.to_radians());
        // Every second column: each run splits where it skips.
        let even = within(&runs, |c, _| c % 2 == 0);
        let starts: Vec<(u32, u32, u32)> = even.iter().map(|r| (r.row, r.start, r.end)).collect();
        assert_eq!(
            starts,
            vec![(0, 0, 1), (0, 4, 5), (0, 6, 7), (1, 2, 3), (1, 6, 7)]
        );
    }

    #[test]
    fn a_ring_of_sources_joins_through_its_chain_of_neighbours() {
        // Single linkage: a joins b, b joins c, though a and c are far.
        let mask = ["#...#...#...#"];
        let pixels = View::new(Projection::Equidistant, 13.0).pixels(13, 1);
        let (_, groups) = find(&mask, &pixels, 4.5f64.to_radians());
        assert_eq!(groups, vec![0, 0, 0, 0]);
    }
}
