//! aureole as an OpenFX 1.4 image effect (`org.aureole.glare`): the
//! library's camera on a compositor's node graph, in the filter and
//! general contexts, on float RGBA or RGB scene-linear light.
//!
//! The host finds `OfxGetNumberOfPlugins` and `OfxGetPlugin` in the
//! bundle's binary, gives the plugin its suites through `setHost`, and
//! calls actions on the main entry. Every action is answered with a
//! status: what went wrong is posted through the message suite in one
//! line, and a panic never crosses into the host.

mod describe;
mod effects;
mod host;
mod instance;
mod memory;
mod render;
mod settings;

use std::ffi::{c_int, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use abi::{names, Handle, OfxHost, OfxPlugin, OfxStatus};
pub use aureole_ofx_abi as abi;
use host::{Failure, Result};

/// The plugin's identifier, stable across versions: hosts save projects
/// with it.
pub const IDENTIFIER: &CStr = c"org.aureole.glare";

#[global_allocator]
static MEMORY: memory::Reusing = memory::Reusing::new();

static PLUGIN: OfxPlugin = OfxPlugin {
    plugin_api: names::IMAGE_EFFECT_PLUGIN_API.as_ptr(),
    api_version: 1,
    plugin_identifier: IDENTIFIER.as_ptr(),
    plugin_version_major: 1,
    plugin_version_minor: 0,
    set_host,
    main_entry,
};

/// How many plugins the binary holds.
#[no_mangle]
pub extern "C" fn OfxGetNumberOfPlugins() -> c_int {
    1
}

/// The plugin at `index`; null past the last.
#[no_mangle]
pub extern "C" fn OfxGetPlugin(index: c_int) -> *const OfxPlugin {
    if index == 0 {
        &PLUGIN
    } else {
        std::ptr::null()
    }
}

unsafe extern "C" fn set_host(host: *mut OfxHost) {
    host::set_host(host);
}

unsafe extern "C" fn main_entry(
    action: *const std::ffi::c_char,
    handle: *const c_void,
    in_args: Handle,
    out_args: Handle,
) -> OfxStatus {
    let effect = handle.cast_mut();
    if action.is_null() {
        return abi::STAT_ERR_BAD_HANDLE;
    }
    // SAFETY: the host passes a C string naming the action.
    let action = unsafe { CStr::from_ptr(action) };
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        dispatch(action, effect, in_args, out_args)
    }));
    match outcome {
        Ok(Ok(status)) => status,
        Ok(Err(Failure { status, message })) => {
            if let Some(message) = message {
                host::post(effect, names::MESSAGE_ERROR, &message);
            }
            status
        }
        Err(panic) => {
            let why = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            host::post(
                effect,
                names::MESSAGE_ERROR,
                &format!(
                    "aureole: internal error in {}: {why}",
                    action.to_string_lossy()
                ),
            );
            abi::STAT_FAILED
        }
    }
}

/// Runs `action`: OK, the default reply for what the plugin leaves to the
/// host, or a failure.
fn dispatch(action: &CStr, effect: Handle, in_args: Handle, out_args: Handle) -> Result<OfxStatus> {
    if action == names::ACTION_LOAD {
        return host::load().map(|()| abi::STAT_OK);
    }
    let suites = host::suites()?;
    let on_effect = || -> Result<()> {
        if effect.is_null() {
            Err(Failure::status(
                abi::STAT_ERR_BAD_HANDLE,
                "the host gave no effect handle",
            ))
        } else {
            Ok(())
        }
    };
    match action {
        a if a == names::ACTION_UNLOAD => {
            host::unload();
            MEMORY.release();
        }
        a if a == names::ACTION_DESCRIBE => {
            on_effect()?;
            describe::describe(effect, &suites)?;
        }
        a if a == names::ACTION_DESCRIBE_IN_CONTEXT => {
            on_effect()?;
            describe::describe_in_context(effect, in_args, &suites)?;
        }
        a if a == names::ACTION_CREATE_INSTANCE => {
            on_effect()?;
            instance::Instance::create(effect, &suites)?;
        }
        a if a == names::ACTION_DESTROY_INSTANCE => {
            on_effect()?;
            instance::Instance::destroy(effect, &suites)?;
            if instance::none_live() {
                MEMORY.release();
            }
        }
        a if a == names::ACTION_PURGE_CACHES => {
            on_effect()?;
            instance::Instance::of(effect, &suites)?.purge();
            MEMORY.release();
        }
        a if a == names::ACTION_GET_REGION_OF_DEFINITION => {
            on_effect()?;
            instance::Instance::of(effect, &suites)?;
            let property = names::EFFECT_REGION_OF_DEFINITION;
            return render::whole_source(effect, (in_args, out_args), property, &suites);
        }
        a if a == names::ACTION_GET_REGIONS_OF_INTEREST => {
            on_effect()?;
            instance::Instance::of(effect, &suites)?;
            let property = names::SOURCE_REGION_OF_INTEREST;
            return render::whole_source(effect, (in_args, out_args), property, &suites);
        }
        a if a == names::ACTION_BEGIN_SEQUENCE_RENDER || a == names::ACTION_END_SEQUENCE_RENDER => {
            // The kept plan serves the whole sequence; nothing to set up.
            on_effect()?;
            instance::Instance::of(effect, &suites)?;
        }
        a if a == names::ACTION_RENDER => {
            on_effect()?;
            render::render(effect, in_args, &suites)?;
        }
        _ => return Ok(abi::STAT_REPLY_DEFAULT),
    }
    Ok(abi::STAT_OK)
}
