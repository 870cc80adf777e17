//! The host as the plugin sees it: the suites fetched at load, property
//! sets read and written through them, messages and the abort flag. Every
//! call's status is checked: a host that lacks a property or refuses a
//! value gives a [`Failure`] naming it, never a crash.

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::sync::RwLock;

use crate::abi::{self, names, Handle, OfxHost, OfxStatus};

/// Why an action failed: the status for the host and, where a person
/// should read it, the one line that says why.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    pub status: OfxStatus,
    pub message: Option<String>,
}

impl Failure {
    /// A failure the user should hear about.
    pub fn said(message: impl Into<String>) -> Failure {
        Failure {
            status: abi::STAT_FAILED,
            message: Some(message.into()),
        }
    }

    /// The library's (or a file's) error, on one line as a host's message
    /// box shows it.
    pub fn library(error: impl std::fmt::Display) -> Failure {
        let line = format!("aureole: {error}");
        Failure::said(line.split_whitespace().collect::<Vec<_>>().join(" "))
    }

    /// A failure in the dialogue with the host, returned as its status.
    pub fn status(status: OfxStatus, what: impl Into<String>) -> Failure {
        Failure {
            status,
            message: Some(what.into()),
        }
    }
}

pub type Result<T> = std::result::Result<T, Failure>;

/// The suites the plugin uses, fetched once at load.
#[derive(Clone, Copy)]
pub struct Suites {
    pub property: &'static abi::OfxPropertySuiteV1,
    pub effect: &'static abi::OfxImageEffectSuiteV1,
    pub parameter: &'static abi::OfxParameterSuiteV1,
    pub message: Option<&'static abi::OfxMessageSuiteV1>,
}

// The suites are tables of functions the host keeps for as long as the
// plugin is loaded; the specification lets any thread call them.
unsafe impl Send for Suites {}
unsafe impl Sync for Suites {}

/// The host `setHost` gave, and the suites fetched from it at load.
struct Connection {
    host: *const OfxHost,
    suites: Option<Suites>,
}

unsafe impl Send for Connection {}
unsafe impl Sync for Connection {}

static CONNECTION: RwLock<Connection> = RwLock::new(Connection {
    host: std::ptr::null(),
    suites: None,
});

/// Keeps the host's pointer (`OfxPlugin::setHost`): nothing is called yet.
pub fn set_host(host: *const OfxHost) {
    let mut connection = CONNECTION.write().unwrap_or_else(|p| p.into_inner());
    connection.host = host;
    connection.suites = None;
}

/// Fetches the suites (`kOfxActionLoad`); a host without one the plugin
/// needs is told which.
pub fn load() -> Result<()> {
    let mut connection = CONNECTION.write().unwrap_or_else(|p| p.into_inner());
    if connection.host.is_null() {
        return Err(Failure::status(
            abi::STAT_ERR_MISSING_HOST_FEATURE,
            "the host called load before setHost",
        ));
    }
    // SAFETY: the host promised the struct lives while the plugin is loaded.
    let host = unsafe { &*connection.host };
    let fetch = |name: &CStr, version: c_int| -> *const c_void {
        // SAFETY: the host's fetcher takes its own handle and a C string.
        unsafe { (host.fetch_suite)(host.host, name.as_ptr(), version) }
    };
    let need = |name: &CStr| -> Result<*const c_void> {
        let suite = fetch(name, 1);
        if suite.is_null() {
            Err(Failure::status(
                abi::STAT_ERR_MISSING_HOST_FEATURE,
                format!("the host has no {} version 1", name.to_string_lossy()),
            ))
        } else {
            Ok(suite)
        }
    };
    // SAFETY: a suite fetched under a name and version has that layout.
    let suites = unsafe {
        Suites {
            property: &*need(names::PROPERTY_SUITE)?.cast(),
            effect: &*need(names::IMAGE_EFFECT_SUITE)?.cast(),
            parameter: &*need(names::PARAMETER_SUITE)?.cast(),
            message: fetch(names::MESSAGE_SUITE, 1)
                .cast::<abi::OfxMessageSuiteV1>()
                .as_ref(),
        }
    };
    connection.suites = Some(suites);
    Ok(())
}

/// Forgets the suites (`kOfxActionUnload`).
pub fn unload() {
    let mut connection = CONNECTION.write().unwrap_or_else(|p| p.into_inner());
    connection.suites = None;
}

/// The suites, once loaded.
pub fn suites() -> Result<Suites> {
    CONNECTION
        .read()
        .unwrap_or_else(|p| p.into_inner())
        .suites
        .ok_or_else(|| {
            Failure::status(
                abi::STAT_FAILED,
                "the host called an action before OfxActionLoad",
            )
        })
}

/// Turns a host's status into a [`Result`], naming what was asked.
fn checked(status: OfxStatus, what: impl FnOnce() -> String) -> Result<()> {
    if status == abi::STAT_OK {
        Ok(())
    } else {
        Err(Failure::status(status, what()))
    }
}

/// A property set of the host's.
#[derive(Clone, Copy)]
pub struct Props {
    handle: Handle,
    suite: &'static abi::OfxPropertySuiteV1,
}

impl Props {
    /// The set behind `handle`; a null handle is refused here.
    pub fn new(handle: Handle, suites: &Suites) -> Result<Props> {
        if handle.is_null() {
            return Err(Failure::status(
                abi::STAT_ERR_BAD_HANDLE,
                "the host gave no property set",
            ));
        }
        Ok(Props {
            handle,
            suite: suites.property,
        })
    }

    fn missing(name: &CStr, index: c_int) -> impl FnOnce() -> String + '_ {
        move || format!("the host's property {} [{index}]", name.to_string_lossy())
    }

    pub fn int(&self, name: &CStr, index: c_int) -> Result<c_int> {
        let mut value = 0;
        // SAFETY: the suite's contract; `value` outlives the call.
        let status =
            unsafe { (self.suite.prop_get_int)(self.handle, name.as_ptr(), index, &mut value) };
        checked(status, Self::missing(name, index)).map(|()| value)
    }

    pub fn double(&self, name: &CStr, index: c_int) -> Result<f64> {
        let mut value = 0.0;
        // SAFETY: as for `int`.
        let status =
            unsafe { (self.suite.prop_get_double)(self.handle, name.as_ptr(), index, &mut value) };
        checked(status, Self::missing(name, index)).map(|()| value)
    }

    pub fn pointer(&self, name: &CStr, index: c_int) -> Result<*mut c_void> {
        let mut value = std::ptr::null_mut();
        // SAFETY: as for `int`.
        let status =
            unsafe { (self.suite.prop_get_pointer)(self.handle, name.as_ptr(), index, &mut value) };
        checked(status, Self::missing(name, index)).map(|()| value)
    }

    pub fn string(&self, name: &CStr, index: c_int) -> Result<String> {
        let mut value: *mut c_char = std::ptr::null_mut();
        // SAFETY: as for `int`; the host keeps the string while the set lives.
        let status =
            unsafe { (self.suite.prop_get_string)(self.handle, name.as_ptr(), index, &mut value) };
        checked(status, Self::missing(name, index))?;
        if value.is_null() {
            return Err(Failure::status(
                abi::STAT_ERR_VALUE,
                Self::missing(name, index)(),
            ));
        }
        // SAFETY: a non-null C string from the host.
        Ok(unsafe { CStr::from_ptr(value) }
            .to_string_lossy()
            .into_owned())
    }

    /// `N` doubles, as a rectangle or a scale is read.
    pub fn doubles<const N: usize>(&self, name: &CStr) -> Result<[f64; N]> {
        let mut values = [0.0; N];
        for (i, value) in values.iter_mut().enumerate() {
            *value = self.double(name, i as c_int)?;
        }
        Ok(values)
    }

    pub fn ints<const N: usize>(&self, name: &CStr) -> Result<[c_int; N]> {
        let mut values = [0; N];
        for (i, value) in values.iter_mut().enumerate() {
            *value = self.int(name, i as c_int)?;
        }
        Ok(values)
    }

    pub fn set_int(&self, name: &CStr, index: c_int, value: c_int) -> Result<()> {
        // SAFETY: the suite's contract.
        let status = unsafe { (self.suite.prop_set_int)(self.handle, name.as_ptr(), index, value) };
        checked(status, Self::missing(name, index))
    }

    pub fn set_double(&self, name: &CStr, index: c_int, value: f64) -> Result<()> {
        // SAFETY: the suite's contract.
        let status =
            unsafe { (self.suite.prop_set_double)(self.handle, name.as_ptr(), index, value) };
        checked(status, Self::missing(name, index))
    }

    pub fn set_pointer(&self, name: &CStr, index: c_int, value: *mut c_void) -> Result<()> {
        // SAFETY: the suite's contract.
        let status =
            unsafe { (self.suite.prop_set_pointer)(self.handle, name.as_ptr(), index, value) };
        checked(status, Self::missing(name, index))
    }

    pub fn set_string(&self, name: &CStr, index: c_int, value: &str) -> Result<()> {
        let value = CString::new(value.replace('\0', " ")).unwrap_or_default();
        // SAFETY: the host copies the string during the call.
        let status = unsafe {
            (self.suite.prop_set_string)(self.handle, name.as_ptr(), index, value.as_ptr())
        };
        checked(status, Self::missing(name, index))
    }

    /// Several strings, from index 0.
    pub fn set_strings(&self, name: &CStr, values: &[&CStr]) -> Result<()> {
        for (i, value) in values.iter().enumerate() {
            // SAFETY: the host copies the string during the call.
            let status = unsafe {
                (self.suite.prop_set_string)(self.handle, name.as_ptr(), i as c_int, value.as_ptr())
            };
            checked(status, Self::missing(name, i as c_int))?;
        }
        Ok(())
    }

    pub fn set_doubles(&self, name: &CStr, values: &[f64]) -> Result<()> {
        values
            .iter()
            .enumerate()
            .try_for_each(|(i, &v)| self.set_double(name, i as c_int, v))
    }
}

/// The property set of the effect (descriptor or instance) `effect`.
pub fn effect_props(effect: Handle, suites: &Suites) -> Result<Props> {
    let mut props = std::ptr::null_mut();
    // SAFETY: the suite's contract; the host checks its handle.
    let status = unsafe { (suites.effect.get_property_set)(effect, &mut props) };
    checked(status, || "the effect's property set".into())?;
    Props::new(props, suites)
}

/// Posts `text` to the user as an error (or a warning) about `effect`,
/// when the host has a message suite.
pub fn post(effect: Handle, kind: &CStr, text: &str) {
    let Ok(suites) = suites() else { return };
    let Some(messages) = suites.message else {
        return;
    };
    let line = CString::new(text.replace('\0', " ")).unwrap_or_default();
    // SAFETY: "%s" with one C string, as printf reads it.
    unsafe {
        (messages.message)(
            effect,
            kind.as_ptr(),
            crate::IDENTIFIER.as_ptr(),
            c"%s".as_ptr(),
            line.as_ptr(),
        );
    }
}

/// Whether the host asks the render of `effect` to stop.
pub fn aborted(effect: Handle, suites: &Suites) -> bool {
    // SAFETY: the suite's contract.
    unsafe { (suites.effect.abort)(effect) != 0 }
}
