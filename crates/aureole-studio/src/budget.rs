//! One memory budget for every render and export of a studio: each takes
//! its estimated peak from the budget before its large buffers, and gives
//! it back when it ends, so that six exports started together run as the
//! budget allows instead of all at once. What is kept between renders (a
//! session's kernel and spectra) holds its lease too, and is given up when
//! another job would otherwise wait ([`Budget::on_shortage`]).

use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use aureole::memory::format_bytes;
use aureole::Cancel;

use crate::error::StudioError;
use crate::locked;

/// How often a waiting job looks at its cancellation.
const POLL: Duration = Duration::from_millis(100);

/// The bytes a studio's jobs may hold together.
pub struct Budget {
    total: u64,
    used: Mutex<u64>,
    freed: Condvar,
    /// Gives back what is kept only to be reused, when a job must wait.
    reclaim: Mutex<Option<Reclaim>>,
}

type Reclaim = Box<dyn Fn() + Send + Sync>;

/// Bytes taken from a [`Budget`], given back when dropped.
pub struct Lease {
    budget: Arc<Budget>,
    bytes: u64,
}

impl Drop for Lease {
    fn drop(&mut self) {
        let mut used = locked(&self.budget.used);
        *used -= self.bytes;
        self.budget.freed.notify_all();
    }
}

impl Budget {
    /// A budget of `total` bytes.
    pub fn new(total: u64) -> Arc<Budget> {
        reuse_freed_buffers();
        Arc::new(Budget {
            total,
            used: Mutex::new(0),
            freed: Condvar::new(),
            reclaim: Mutex::new(None),
        })
    }

    /// `reclaim` is called when a job would have to wait, to give back
    /// leases held only for reuse (it must not wait for the budget).
    pub fn on_shortage(&self, reclaim: impl Fn() + Send + Sync + 'static) {
        *locked(&self.reclaim) = Some(Box::new(reclaim));
    }

    /// The bytes of the whole budget.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// The bytes no job holds now.
    pub fn available(&self) -> u64 {
        self.total.saturating_sub(*locked(&self.used))
    }

    /// Takes `bytes` (at most the whole budget: a job larger than it is
    /// refused by its session, with the reason), waiting while other jobs
    /// hold too much, until `cancel` is raised or, with `patience`, that
    /// long has passed: then the studio is busy (503). `waiting` hears
    /// when it has to wait.
    pub fn lease(
        self: &Arc<Self>,
        bytes: u64,
        cancel: &Cancel,
        patience: Option<Duration>,
        waiting: impl FnOnce(),
    ) -> Result<Lease, StudioError> {
        let bytes = bytes.min(self.total);
        let start = Instant::now();
        if *locked(&self.used) + bytes > self.total {
            // Outside the lock: what it gives back takes the lock to return.
            if let Some(reclaim) = locked(&self.reclaim).as_ref() {
                reclaim();
            }
        }
        let mut used = locked(&self.used);
        let mut waiting = Some(waiting);
        while *used + bytes > self.total {
            if let Some(say) = waiting.take() {
                say();
            }
            cancel.check()?;
            if patience.is_some_and(|p| start.elapsed() >= p) {
                return Err(StudioError::Busy(format!(
                    "the studio's memory is taken by other renders and exports ({} of {} in use, this one needs {}): try again when they end",
                    format_bytes(*used),
                    format_bytes(self.total),
                    format_bytes(bytes)
                )));
            }
            used = self
                .freed
                .wait_timeout(used, POLL)
                .map(|(guard, _)| guard)
                .unwrap_or_else(|poisoned| poisoned.into_inner().0);
        }
        *used += bytes;
        Ok(Lease {
            budget: self.clone(),
            bytes,
        })
    }
}

/// Serves buffers below 64 MiB from one heap for every thread, which
/// keeps up to 128 MiB freed at its top. glibc's own policy raises its
/// threshold for mapping a buffer on its own as larger ones are freed,
/// and gives an arena to each thread: each kept what its threads freed
/// (1 GB under a 512 MB budget in the HTTP fuzz test) until the
/// threshold was fixed at 1 MiB, after which every preview mapped its
/// buffers afresh and took their pages again through page faults and the
/// kernel's zeroing, half of a 1280×720 bloom preview's time
/// (`bench/studio_latency.py`). With one arena, what one render frees the
/// next takes, whichever threads ran them; the largest buffers (a 4K
/// frame's spectra) are still mapped and given back when freed; the fuzz
/// test's peak is 0.64 GB under its 512 MB budget (0.74 GB before).
fn reuse_freed_buffers() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            #[allow(unsafe_code)]
            // SAFETY: mallopt only sets allocator parameters; it is
            // called once, and glibc serialises it with allocations.
            unsafe {
                libc::mallopt(libc::M_MMAP_THRESHOLD, 64 << 20);
                libc::mallopt(libc::M_ARENA_MAX, 1);
                libc::mallopt(libc::M_TRIM_THRESHOLD, 128 << 20);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leases_wait_for_each_other_and_give_back() {
        let budget = Budget::new(100);
        let cancel = Cancel::new();
        let first = budget.lease(70, &cancel, None, || {}).unwrap();
        let refused = budget.lease(40, &cancel, Some(Duration::from_millis(200)), || {});
        assert!(matches!(refused, Err(StudioError::Busy(_))));
        let waiting = {
            let budget = budget.clone();
            std::thread::spawn(move || {
                budget
                    .lease(40, &Cancel::new(), None, || {})
                    .map(|l| l.bytes)
            })
        };
        std::thread::sleep(Duration::from_millis(150));
        drop(first);
        assert_eq!(waiting.join().unwrap().unwrap(), 40);
        assert_eq!(*locked(&budget.used), 0);
    }

    #[test]
    fn a_shortage_gives_back_what_is_kept_for_reuse() {
        let budget = Budget::new(100);
        let kept = Arc::new(Mutex::new(Some(
            budget.lease(80, &Cancel::new(), None, || {}).unwrap(),
        )));
        let held = kept.clone();
        budget.on_shortage(move || drop(locked(&held).take()));
        // Fits beside it: nothing given back.
        let small = budget.lease(20, &Cancel::new(), None, || {}).unwrap();
        assert!(locked(&kept).is_some());
        drop(small);
        let large = budget.lease(50, &Cancel::new(), Some(Duration::from_millis(200)), || {});
        assert_eq!(large.unwrap().bytes, 50);
        assert!(locked(&kept).is_none());
    }

    #[test]
    fn a_cancelled_wait_ends() {
        let budget = Budget::new(10);
        let _held = budget.lease(10, &Cancel::new(), None, || {}).unwrap();
        let cancel = Cancel::new();
        cancel.cancel();
        assert!(matches!(
            budget.lease(5, &cancel, None, || {}),
            Err(StudioError::Superseded)
        ));
    }

    #[test]
    fn a_job_larger_than_the_budget_takes_all_of_it() {
        let budget = Budget::new(10);
        let lease = budget.lease(50, &Cancel::new(), None, || {}).unwrap();
        assert_eq!(lease.bytes, 10);
    }
}
