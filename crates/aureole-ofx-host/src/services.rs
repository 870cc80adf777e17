//! The memory, multi-thread and message suites.

use std::alloc::Layout;
use std::cell::Cell;
use std::collections::HashMap;
use std::ffi::{c_char, c_int, c_uint, c_void, CStr};
use std::sync::{Condvar, Mutex};
use std::thread::ThreadId;

use aureole_ofx_abi::{self as abi, Handle, OfxStatus, ThreadFunction};

use crate::effect::Effect;
use crate::props::{live, register, unregister, Kind};

/// Each block's layout, to free it.
static BLOCKS: Mutex<Option<HashMap<usize, Layout>>> = Mutex::new(None);

/// Allocates `bytes`, aligned for any pixel type, into `out`.
pub fn alloc(bytes: usize, out: *mut *mut c_void) -> OfxStatus {
    if out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    let Ok(layout) = Layout::from_size_align(bytes.max(1), 64) else {
        return abi::STAT_ERR_MEMORY;
    };
    // SAFETY: a layout of non-zero size.
    let block = unsafe { std::alloc::alloc(layout) };
    if block.is_null() {
        return abi::STAT_ERR_MEMORY;
    }
    BLOCKS
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .get_or_insert_with(HashMap::new)
        .insert(block as usize, layout);
    register(block, Kind::Memory);
    // SAFETY: the plugin's out pointer, checked non-null.
    unsafe { out.write(block.cast()) };
    abi::STAT_OK
}

/// Frees a block [`alloc`] gave.
pub fn free(block: *mut c_void) -> OfxStatus {
    let layout = BLOCKS
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .as_mut()
        .and_then(|b| b.remove(&(block as usize)));
    let Some(layout) = layout else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    unregister(block);
    // SAFETY: allocated by `alloc` with this layout, freed once.
    unsafe { std::alloc::dealloc(block.cast(), layout) };
    abi::STAT_OK
}

unsafe extern "C" fn memory_alloc(
    _handle: Handle,
    bytes: usize,
    out: *mut *mut c_void,
) -> OfxStatus {
    alloc(bytes, out)
}

unsafe extern "C" fn memory_free(block: *mut c_void) -> OfxStatus {
    free(block)
}

pub static MEMORY_SUITE: abi::OfxMemorySuiteV1 = abi::OfxMemorySuiteV1 {
    memory_alloc,
    memory_free,
};

thread_local! {
    /// The index multiThread gave this thread, on threads it spawned.
    static SPAWNED: Cell<Option<c_uint>> = const { Cell::new(None) };
}

/// The plugin's argument, sent to the threads that run its function.
struct Argument(*mut c_void);
unsafe impl Send for Argument {}
unsafe impl Sync for Argument {}

unsafe extern "C" fn multi_thread(
    function: ThreadFunction,
    threads: c_uint,
    argument: *mut c_void,
) -> OfxStatus {
    if SPAWNED.with(Cell::get).is_some() {
        return abi::STAT_ERR_EXISTS;
    }
    let argument = Argument(argument);
    let count = threads.max(1);
    std::thread::scope(|scope| {
        for index in 0..count {
            let argument = &argument;
            scope.spawn(move || {
                SPAWNED.with(|s| s.set(Some(index)));
                // SAFETY: the plugin's function, called as the suite says.
                unsafe { function(index, count, argument.0) };
            });
        }
    });
    abi::STAT_OK
}

unsafe extern "C" fn num_cpus(out: *mut c_uint) -> OfxStatus {
    if out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    let n = std::thread::available_parallelism().map_or(1, |n| n.get()) as c_uint;
    // SAFETY: the plugin's out pointer, checked non-null.
    unsafe { out.write(n) };
    abi::STAT_OK
}

unsafe extern "C" fn thread_index(out: *mut c_uint) -> OfxStatus {
    if out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    // SAFETY: the plugin's out pointer, checked non-null.
    unsafe { out.write(SPAWNED.with(Cell::get).unwrap_or(0)) };
    abi::STAT_OK
}

unsafe extern "C" fn is_spawned() -> c_int {
    SPAWNED.with(Cell::get).is_some() as c_int
}

/// A recursive mutex: the thread that holds it may lock it again.
#[derive(Default)]
struct Recursive {
    held: Mutex<Option<(ThreadId, usize)>>,
    freed: Condvar,
}

impl Recursive {
    fn lock(&self, wait: bool) -> bool {
        let me = std::thread::current().id();
        let mut held = self.held.lock().unwrap_or_else(|p| p.into_inner());
        loop {
            match *held {
                None => {
                    *held = Some((me, 1));
                    return true;
                }
                Some((owner, n)) if owner == me => {
                    *held = Some((owner, n + 1));
                    return true;
                }
                Some(_) if !wait => return false,
                Some(_) => held = self.freed.wait(held).unwrap_or_else(|p| p.into_inner()),
            }
        }
    }

    fn unlock(&self) -> bool {
        let me = std::thread::current().id();
        let mut held = self.held.lock().unwrap_or_else(|p| p.into_inner());
        match *held {
            Some((owner, n)) if owner == me => {
                *held = (n > 1).then_some((owner, n - 1));
                self.freed.notify_one();
                true
            }
            _ => false,
        }
    }
}

unsafe extern "C" fn mutex_create(out: *mut Handle, locks: c_int) -> OfxStatus {
    if out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    let mutex = Box::into_raw(Box::<Recursive>::default());
    register(mutex, Kind::Memory);
    // SAFETY: just made; a count below 0 is taken as 0.
    for _ in 0..locks.max(0) {
        unsafe { &*mutex }.lock(true);
    }
    // SAFETY: the plugin's out pointer, checked non-null.
    unsafe { out.write(mutex.cast()) };
    abi::STAT_OK
}

fn mutex<'a>(handle: Handle) -> Option<&'a Recursive> {
    live::<Recursive>(handle, Kind::Memory)
}

unsafe extern "C" fn mutex_destroy(handle: Handle) -> OfxStatus {
    if mutex(handle).is_none() {
        return abi::STAT_ERR_BAD_HANDLE;
    }
    unregister(handle);
    // SAFETY: made by mutex_create, destroyed once (unregistered above).
    drop(unsafe { Box::from_raw(handle.cast::<Recursive>()) });
    abi::STAT_OK
}

unsafe extern "C" fn mutex_lock(handle: Handle) -> OfxStatus {
    mutex(handle).map_or(abi::STAT_ERR_BAD_HANDLE, |m| {
        m.lock(true);
        abi::STAT_OK
    })
}

unsafe extern "C" fn mutex_unlock(handle: Handle) -> OfxStatus {
    mutex(handle).map_or(abi::STAT_ERR_BAD_HANDLE, |m| {
        if m.unlock() {
            abi::STAT_OK
        } else {
            abi::STAT_FAILED
        }
    })
}

unsafe extern "C" fn mutex_try_lock(handle: Handle) -> OfxStatus {
    mutex(handle).map_or(abi::STAT_ERR_BAD_HANDLE, |m| {
        if m.lock(false) {
            abi::STAT_OK
        } else {
            abi::STAT_FAILED
        }
    })
}

pub static MULTI_THREAD_SUITE: abi::OfxMultiThreadSuiteV1 = abi::OfxMultiThreadSuiteV1 {
    multi_thread,
    multi_thread_num_cpus: num_cpus,
    multi_thread_index: thread_index,
    multi_thread_is_spawned_thread: is_spawned,
    mutex_create,
    mutex_destroy,
    mutex_lock,
    mutex_unlock,
    mutex_try_lock,
};

/// What the plugin posted with no effect to post it on.
pub static UNATTACHED: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());

/// `message(handle, type, id, format, ...)`: the host formats `%s` with
/// the first argument (the one conversion the plugin uses) and shows any
/// other format as it is. As for the parameter suite, the variadic
/// argument is read as a fixed one (x86-64 System V).
unsafe extern "C" fn message(
    effect: Handle,
    kind: *const c_char,
    _id: *const c_char,
    format: *const c_char,
    first: *const c_char,
) -> OfxStatus {
    // SAFETY: the plugin's C strings, each checked non-null.
    let read = |s: *const c_char| {
        (!s.is_null()).then(|| unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned())
    };
    let (Some(kind), Some(format)) = (read(kind), read(format)) else {
        return abi::STAT_ERR_VALUE;
    };
    let text = if format == "%s" {
        read(first).unwrap_or_default()
    } else {
        format
    };
    match live::<Effect>(effect, Kind::Effect) {
        Some(effect) => effect
            .messages
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((kind, text)),
        None => UNATTACHED
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((kind, text)),
    }
    abi::STAT_OK
}

type Message = unsafe extern "C" fn(
    Handle,
    *const c_char,
    *const c_char,
    *const c_char,
    *const c_char,
) -> OfxStatus;
type VariadicMessage =
    unsafe extern "C" fn(Handle, *const c_char, *const c_char, *const c_char, ...) -> OfxStatus;

/// The message suite the host hands out.
pub fn message_suite() -> abi::OfxMessageSuiteV1 {
    abi::OfxMessageSuiteV1 {
        // SAFETY: see `message`.
        message: unsafe { std::mem::transmute::<Message, VariadicMessage>(message) },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU32, Ordering};

    #[test]
    fn memory_is_given_aligned_and_taken_back_once() {
        let mut block = std::ptr::null_mut();
        // SAFETY: the suite's own functions, as a plugin calls them.
        unsafe {
            assert_eq!(
                (MEMORY_SUITE.memory_alloc)(std::ptr::null_mut(), 1 << 20, &mut block),
                abi::STAT_OK
            );
            assert_eq!(block as usize % 64, 0);
            block.cast::<u8>().write_bytes(7, 1 << 20);
            assert_eq!((MEMORY_SUITE.memory_free)(block), abi::STAT_OK);
            assert_eq!((MEMORY_SUITE.memory_free)(block), abi::STAT_ERR_BAD_HANDLE);
        }
    }

    unsafe extern "C" fn count(index: c_uint, total: c_uint, argument: *mut c_void) {
        // SAFETY: the test passes an AtomicU32.
        let sum = unsafe { &*argument.cast::<AtomicU32>() };
        let mut me = 0;
        // SAFETY: the suite's own functions.
        unsafe {
            assert_eq!(
                (MULTI_THREAD_SUITE.multi_thread_index)(&mut me),
                abi::STAT_OK
            );
            assert_eq!((MULTI_THREAD_SUITE.multi_thread_is_spawned_thread)(), 1);
            // A spawned thread may not spawn again.
            assert_eq!(
                (MULTI_THREAD_SUITE.multi_thread)(count, 2, argument),
                abi::STAT_ERR_EXISTS
            );
        }
        assert_eq!(me, index);
        assert_eq!(total, 4);
        sum.fetch_add(1 << index, Ordering::Relaxed);
    }

    #[test]
    fn multi_thread_runs_each_index_once_and_mutexes_are_recursive() {
        let sum = AtomicU32::new(0);
        let argument = (&sum as *const AtomicU32).cast_mut().cast();
        let mut mutex = std::ptr::null_mut();
        // SAFETY: the suite's own functions, as a plugin calls them.
        unsafe {
            let s = &MULTI_THREAD_SUITE;
            assert_eq!((s.multi_thread)(count, 4, argument), abi::STAT_OK);
            assert_eq!(sum.load(Ordering::Relaxed), 0b1111);
            assert_eq!((s.multi_thread_is_spawned_thread)(), 0);
            let mut cpus = 0;
            assert_eq!((s.multi_thread_num_cpus)(&mut cpus), abi::STAT_OK);
            assert!(cpus >= 1);
            assert_eq!((s.mutex_create)(&mut mutex, 1), abi::STAT_OK);
            assert_eq!((s.mutex_lock)(mutex), abi::STAT_OK);
            let other = mutex as usize;
            let tried = std::thread::spawn(move || (s.mutex_try_lock)(other as Handle)).join();
            assert_eq!(tried.ok(), Some(abi::STAT_FAILED));
            assert_eq!((s.mutex_unlock)(mutex), abi::STAT_OK);
            assert_eq!((s.mutex_unlock)(mutex), abi::STAT_OK);
            assert_eq!((s.mutex_unlock)(mutex), abi::STAT_FAILED);
            assert_eq!((s.mutex_destroy)(mutex), abi::STAT_OK);
            assert_eq!((s.mutex_lock)(mutex), abi::STAT_ERR_BAD_HANDLE);
        }
    }
}
