//! Talking to a long computation while it runs: how far it has come, and a
//! flag that stops it. Every long loop of the library (rasterising a
//! kernel, each convolution pass, splatting, the f64 route) checks the flag
//! at least every few milliseconds of work, so that a cancelled run returns
//! [`Error::Cancelled`] well within 100 ms.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use rayon::prelude::*;

use crate::error::{Error, Result};

/// Asks a computation to stop. Clones share one flag: a front end keeps one
/// and hands another to the work, and may cancel from any thread (a signal
/// handler, a server task whose client went away, Python's Ctrl-C).
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A flag not yet raised.
    pub fn new() -> Cancel {
        Cancel::default()
    }

    /// Raises the flag: the work stops at its next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether the flag is raised.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// [`Error::Cancelled`] once the flag is raised.
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }
}

/// Progress and cancellation, handed down to every long loop: the loop
/// reports the fraction of its own work done, 0 to 1, and the control maps
/// it into the share of the whole run that the loop was given.
pub struct Control<'a> {
    cancel: Cancel,
    report: Option<&'a mut (dyn FnMut(f64) + 'a)>,
    from: f64,
    to: f64,
}

impl<'a> Control<'a> {
    /// Reports to `report` (the fraction of the whole run, 0 to 1) and
    /// stops when `cancel` is raised.
    pub fn new(cancel: &Cancel, report: &'a mut (dyn FnMut(f64) + 'a)) -> Control<'a> {
        Control {
            cancel: cancel.clone(),
            report: Some(report),
            from: 0.0,
            to: 1.0,
        }
    }

    /// Stops when `cancel` is raised, and reports nothing.
    pub fn quiet(cancel: &Cancel) -> Control<'a> {
        Control {
            cancel: cancel.clone(),
            report: None,
            from: 0.0,
            to: 1.0,
        }
    }

    /// The flag, for the workers of a parallel loop to look at.
    pub fn cancel(&self) -> Cancel {
        self.cancel.clone()
    }

    /// [`Error::Cancelled`] once the run is cancelled.
    pub fn check(&self) -> Result<()> {
        self.cancel.check()
    }

    /// Reports that `fraction` (0 to 1) of this part of the work is done.
    pub fn report(&mut self, fraction: f64) {
        let (from, to) = (self.from, self.to);
        if let Some(report) = self.report.as_deref_mut() {
            report(from + (to - from) * fraction.clamp(0.0, 1.0));
        }
    }

    /// The share of this part from `from` to `to` (fractions of it), for a
    /// step of the work to report into.
    pub fn part(&mut self, from: f64, to: f64) -> Control<'_> {
        let span = self.to - self.from;
        Control {
            cancel: self.cancel.clone(),
            report: self.report.as_deref_mut().map(|report| report as _),
            from: self.from + span * from,
            to: self.from + span * to,
        }
    }
}

/// How many batches a loop over rows is cut into, at most: each batch runs
/// in parallel and ends with a progress report and a check of the flag.
const BATCHES: usize = 64;

/// The fewest rows a batch gives each thread: at the end of a batch the
/// threads wait for its slowest row, so a batch must hold many of them.
const ROWS_PER_THREAD: usize = 32;

/// Runs `work(row index, row)` on every row (`width` items) of `plane` in
/// parallel, in batches that report progress; rows not yet started are
/// skipped once the run is cancelled.
pub(crate) fn for_each_row<T: Send>(
    plane: &mut [T],
    width: usize,
    control: &mut Control,
    work: impl Fn(usize, &mut [T]) + Sync,
) -> Result<()> {
    let mut rows: Vec<&mut [T]> = plane.chunks_mut(width.max(1)).collect();
    for_each(&mut rows, control, |j, row| work(j, row))
}

/// Runs `work(index, item)` on every item in parallel, in batches that
/// report progress; items not yet started are skipped once the run is
/// cancelled.
pub(crate) fn for_each<T: Send>(
    items: &mut [T],
    control: &mut Control,
    work: impl Fn(usize, &mut T) + Sync,
) -> Result<()> {
    let count = items.len();
    let per_batch = count
        .div_ceil(BATCHES)
        .max(ROWS_PER_THREAD * rayon::current_num_threads())
        .max(1);
    let cancel = control.cancel();
    for (batch, chunk) in items.chunks_mut(per_batch).enumerate() {
        control.check()?;
        let first = batch * per_batch;
        chunk.par_iter_mut().enumerate().for_each(|(k, item)| {
            if !cancel.is_cancelled() {
                work(first + k, item);
            }
        });
        control.report(((first + chunk.len()) as f64 / count.max(1) as f64).min(1.0));
    }
    control.check()
}

/// As [`for_each`], for items whose cost varies along the index (a
/// diffraction pattern's rows, dearer near its centre): they are taken in
/// an interleaved order, every batch a sample of the whole range, so that
/// the progress reported follows the work done and not only the count.
pub(crate) fn for_each_interleaved<T: Send>(
    items: &mut [T],
    control: &mut Control,
    work: impl Fn(usize, &mut T) + Sync,
) -> Result<()> {
    let stride = BATCHES.min(items.len()).max(1);
    let mut order: Vec<(usize, &mut T)> = items.iter_mut().enumerate().collect();
    order.sort_by_key(|(i, _)| (i % stride, *i));
    for_each(&mut order, control, |_, (i, item)| work(*i, item))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_report_into_their_share_of_the_whole() {
        let cancel = Cancel::new();
        let mut heard = Vec::new();
        let mut report = |f: f64| heard.push(f);
        let mut control = Control::new(&cancel, &mut report);
        control.part(0.5, 1.0).part(0.0, 0.5).report(1.0);
        control.report(0.25);
        assert_eq!(heard, [0.75, 0.25]);
    }

    #[test]
    fn a_cancelled_loop_stops_and_says_so() {
        let cancel = Cancel::new();
        let mut plane = vec![0u8; 100 * 10];
        let mut control = Control::quiet(&cancel);
        let done = std::sync::atomic::AtomicUsize::new(0);
        let result = for_each_row(&mut plane, 10, &mut control, |j, row| {
            if j == 3 {
                cancel.cancel();
            }
            row[0] = 1;
            done.fetch_add(1, Ordering::Relaxed);
        });
        assert!(matches!(result, Err(Error::Cancelled)));
        assert!(done.into_inner() < 100);
    }

    #[test]
    fn interleaved_items_are_each_visited_once_by_their_own_index() {
        let cancel = Cancel::new();
        let mut heard = Vec::new();
        let mut report = |f: f64| heard.push(f);
        let mut control = Control::new(&cancel, &mut report);
        let mut items: Vec<usize> = vec![0; 1000];
        for_each_interleaved(&mut items, &mut control, |i, item| *item += i + 1).unwrap();
        assert!(items.iter().enumerate().all(|(i, &v)| v == i + 1));
        assert_eq!(heard.last(), Some(&1.0));
    }
}
