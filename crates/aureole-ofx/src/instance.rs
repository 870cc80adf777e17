//! One effect instance's state: the session that holds its camera's plan
//! (kernel and spectra), kept between frames so that a sequence builds its
//! kernel once per camera and frame size. Renders of one instance take
//! turns on it: each is spread over every core by the library, and two at
//! once would hold two 4K plans.

use std::ffi::c_void;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use aureole::{Config, Device, Session};

use crate::abi::{self, names, Handle};
use crate::host::{effect_props, Failure, Result, Suites};

/// How many instances the host holds.
static LIVE: AtomicUsize = AtomicUsize::new(0);

/// Whether the host holds no instance.
pub fn none_live() -> bool {
    LIVE.load(Ordering::Relaxed) == 0
}

/// The session of the camera last rendered.
pub struct Kept {
    /// The composed camera's TOML, its device and render scale.
    pub key: String,
    pub session: Session,
}

/// What the plugin keeps per instance, behind the host's
/// `kOfxPropInstanceData` pointer.
#[derive(Default)]
pub struct Instance {
    pub kept: Mutex<Option<Kept>>,
}

impl Instance {
    /// `kOfxActionCreateInstance`: the state made and handed to the host.
    pub fn create(effect: Handle, suites: &Suites) -> Result<()> {
        let props = effect_props(effect, suites)?;
        if !props.pointer(names::PROP_INSTANCE_DATA, 0)?.is_null() {
            return Err(Failure::status(
                abi::STAT_ERR_EXISTS,
                "aureole: the host created this instance twice",
            ));
        }
        let state = Box::into_raw(Box::new(Instance::default()));
        props
            .set_pointer(names::PROP_INSTANCE_DATA, 0, state.cast::<c_void>())
            .inspect_err(|_| {
                // SAFETY: made just above and never handed out.
                drop(unsafe { Box::from_raw(state) });
            })?;
        LIVE.fetch_add(1, Ordering::Relaxed);
        Ok(())
    }

    /// `kOfxActionDestroyInstance`: the state taken back and freed.
    pub fn destroy(effect: Handle, suites: &Suites) -> Result<()> {
        let props = effect_props(effect, suites)?;
        let state = props.pointer(names::PROP_INSTANCE_DATA, 0)?;
        if state.is_null() {
            return Err(Failure::status(
                abi::STAT_ERR_BAD_HANDLE,
                "aureole: the host destroyed an instance it had not created",
            ));
        }
        props.set_pointer(names::PROP_INSTANCE_DATA, 0, std::ptr::null_mut())?;
        // SAFETY: the pointer `create` gave the host, taken back once: the
        // property now holds null.
        drop(unsafe { Box::from_raw(state.cast::<Instance>()) });
        LIVE.fetch_sub(1, Ordering::Relaxed);
        Ok(())
    }

    /// The state of the instance `effect`, while the host keeps it.
    pub fn of(effect: Handle, suites: &Suites) -> Result<&'static Instance> {
        let state = effect_props(effect, suites)?.pointer(names::PROP_INSTANCE_DATA, 0)?;
        // SAFETY: set by `create`, freed only by `destroy`, which the host
        // calls once no action is running on the instance.
        unsafe { state.cast::<Instance>().as_ref() }.ok_or_else(|| {
            Failure::status(
                abi::STAT_ERR_BAD_HANDLE,
                "aureole: the host called an action on an instance it had not created",
            )
        })
    }

    /// Hands a result's planes back to the kept session, for the next
    /// frame to be written into.
    pub fn recycle(&self, result: aureole::Image) {
        if let Some(kept) = self.kept.lock().unwrap_or_else(|p| p.into_inner()).as_mut() {
            kept.session.recycle(result);
        }
    }

    /// Drops the kept plan (`kOfxActionPurgeCaches`).
    pub fn purge(&self) {
        *self.kept.lock().unwrap_or_else(|p| p.into_inner()) = None;
    }
}

/// A session for `config` on `device`, with the machine's memory budget.
pub fn session(config: Config, device: Device) -> Session {
    Session::new(config)
        .with_memory_limit(aureole_io::limits::default_memory_limit())
        .with_device(device)
}
