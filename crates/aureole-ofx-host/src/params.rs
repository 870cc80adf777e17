//! The parameter suite (`OfxParameterSuiteV1`). The host does not animate:
//! a parameter's value is the same at every time, and the key-frame
//! functions say they are unsupported.
//!
//! The value functions are C variadics. A variadic function cannot be
//! written in stable Rust, so the host's take the pointers a getter is
//! passed as fixed arguments: on x86-64 System V (the ABI the tests run
//! on) a variadic call passes its leading integer and pointer arguments in
//! the same registers as a fixed one, and the time (a double) in the same
//! vector register.

use std::ffi::{c_char, c_int, c_uint, c_void, CStr};

use aureole_ofx_abi::{self as abi, names, Handle, OfxRangeD, OfxStatus, OfxTime};

use crate::effect::{new_param, Param, ParamSet};
use crate::props::{live, Kind, Value};

unsafe extern "C" fn define(
    set: Handle,
    kind: *const c_char,
    name: *const c_char,
    out: *mut Handle,
) -> OfxStatus {
    let Some(set) = live::<ParamSet>(set, Kind::ParamSet) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    if kind.is_null() || name.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    // SAFETY: the plugin's C strings, checked non-null.
    let (kind, name) = unsafe { (CStr::from_ptr(kind), CStr::from_ptr(name)) };
    let known = [
        names::PARAM_TYPE_DOUBLE,
        names::PARAM_TYPE_INTEGER,
        names::PARAM_TYPE_BOOLEAN,
        names::PARAM_TYPE_CHOICE,
        names::PARAM_TYPE_STRING,
        names::PARAM_TYPE_GROUP,
    ];
    if !known.contains(&kind) {
        return abi::STAT_ERR_UNKNOWN;
    }
    let mut params = set.params.lock().unwrap_or_else(|p| p.into_inner());
    if params.iter().any(|(n, _)| n.as_c_str() == name) {
        return abi::STAT_ERR_EXISTS;
    }
    let param = new_param(kind, name);
    if !out.is_null() {
        // SAFETY: the plugin's out pointer, checked non-null.
        unsafe { out.write(param.props.handle()) };
    }
    params.push((name.to_owned(), param));
    abi::STAT_OK
}

unsafe extern "C" fn get_handle(
    set: Handle,
    name: *const c_char,
    out: *mut Handle,
    props: *mut Handle,
) -> OfxStatus {
    let Some(set) = live::<ParamSet>(set, Kind::ParamSet) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    if name.is_null() || out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    // SAFETY: the plugin's C string, checked non-null.
    let name = unsafe { CStr::from_ptr(name) };
    let params = set.params.lock().unwrap_or_else(|p| p.into_inner());
    let Some((_, param)) = params.iter().find(|(n, _)| n.as_c_str() == name) else {
        return abi::STAT_ERR_UNKNOWN;
    };
    // SAFETY: the plugin's out pointers; the parameter lives with its set.
    unsafe {
        out.write((&**param as *const Param).cast_mut().cast());
        if !props.is_null() {
            props.write(param.props.handle());
        }
    }
    abi::STAT_OK
}

unsafe extern "C" fn set_property_set(set: Handle, out: *mut Handle) -> OfxStatus {
    match (live::<ParamSet>(set, Kind::ParamSet), out.is_null()) {
        (Some(set), false) => {
            // SAFETY: the plugin's out pointer, checked non-null.
            unsafe { out.write(set.props.handle()) };
            abi::STAT_OK
        }
        (None, _) => abi::STAT_ERR_BAD_HANDLE,
        (_, true) => abi::STAT_ERR_VALUE,
    }
}

unsafe extern "C" fn property_set(param: Handle, out: *mut Handle) -> OfxStatus {
    match (live::<Param>(param, Kind::Param), out.is_null()) {
        (Some(param), false) => {
            // SAFETY: the plugin's out pointer, checked non-null.
            unsafe { out.write(param.props.handle()) };
            abi::STAT_OK
        }
        (None, _) => abi::STAT_ERR_BAD_HANDLE,
        (_, true) => abi::STAT_ERR_VALUE,
    }
}

/// Writes the parameter's value where its type says the first pointer
/// points: a double, an int, or a C string's address (kept by the host
/// until the value changes).
fn read_value(param: Handle, out: *mut c_void) -> OfxStatus {
    let Some(param) = live::<Param>(param, Kind::Param) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    if out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    let value = param.value.lock().unwrap_or_else(|p| p.into_inner());
    // SAFETY: the plugin passes a pointer of the parameter's type.
    unsafe {
        match &*value {
            Value::Doubles(v) if !v.is_empty() => out.cast::<f64>().write(v[0]),
            Value::Ints(v) if !v.is_empty() => out.cast::<c_int>().write(v[0]),
            Value::Strings(v) if !v.is_empty() => out.cast::<*const c_char>().write(v[0].as_ptr()),
            _ => return abi::STAT_ERR_VALUE,
        }
    }
    abi::STAT_OK
}

unsafe extern "C" fn get_value(param: Handle, out: *mut c_void) -> OfxStatus {
    read_value(param, out)
}

unsafe extern "C" fn get_value_at_time(
    param: Handle,
    _time: OfxTime,
    out: *mut c_void,
) -> OfxStatus {
    read_value(param, out)
}

unsafe extern "C" fn unsupported_timed(_: Handle, _: OfxTime) -> OfxStatus {
    abi::STAT_ERR_UNSUPPORTED
}

unsafe extern "C" fn unsupported_span(_: Handle, _: OfxTime, _: OfxTime) -> OfxStatus {
    abi::STAT_ERR_UNSUPPORTED
}

unsafe extern "C" fn unsupported(_: Handle) -> OfxStatus {
    abi::STAT_ERR_UNSUPPORTED
}

unsafe extern "C" fn num_keys(param: Handle, out: *mut c_uint) -> OfxStatus {
    match (live::<Param>(param, Kind::Param), out.is_null()) {
        (Some(_), false) => {
            // SAFETY: the plugin's out pointer, checked non-null.
            unsafe { out.write(0) };
            abi::STAT_OK
        }
        (None, _) => abi::STAT_ERR_BAD_HANDLE,
        (_, true) => abi::STAT_ERR_VALUE,
    }
}

unsafe extern "C" fn key_time(_: Handle, _: c_uint, _: *mut OfxTime) -> OfxStatus {
    abi::STAT_ERR_BAD_INDEX
}

unsafe extern "C" fn key_index(_: Handle, _: OfxTime, _: c_int, _: *mut c_int) -> OfxStatus {
    abi::STAT_FAILED
}

unsafe extern "C" fn copy(_: Handle, _: Handle, _: OfxTime, _: *const OfxRangeD) -> OfxStatus {
    abi::STAT_ERR_UNSUPPORTED
}

unsafe extern "C" fn edit_begin(_: Handle, _: *const c_char) -> OfxStatus {
    abi::STAT_OK
}

unsafe extern "C" fn edit_end(_: Handle) -> OfxStatus {
    abi::STAT_OK
}

type Getter = unsafe extern "C" fn(Handle, *mut c_void) -> OfxStatus;
type TimedGetter = unsafe extern "C" fn(Handle, OfxTime, *mut c_void) -> OfxStatus;
type Variadic = unsafe extern "C" fn(Handle, ...) -> OfxStatus;
type TimedVariadic = unsafe extern "C" fn(Handle, OfxTime, ...) -> OfxStatus;
type SpanVariadic = unsafe extern "C" fn(Handle, OfxTime, OfxTime, ...) -> OfxStatus;

/// The parameter suite the host hands out.
pub fn suite() -> abi::OfxParameterSuiteV1 {
    // SAFETY: see the module's note: on x86-64 System V a fixed-argument
    // function reads a variadic call's leading arguments where it left them.
    unsafe {
        abi::OfxParameterSuiteV1 {
            param_define: define,
            param_get_handle: get_handle,
            param_set_get_property_set: set_property_set,
            param_get_property_set: property_set,
            param_get_value: std::mem::transmute::<Getter, Variadic>(get_value),
            param_get_value_at_time: std::mem::transmute::<TimedGetter, TimedVariadic>(
                get_value_at_time,
            ),
            param_get_derivative: std::mem::transmute::<
                unsafe extern "C" fn(Handle, OfxTime) -> OfxStatus,
                TimedVariadic,
            >(unsupported_timed),
            param_get_integral: std::mem::transmute::<
                unsafe extern "C" fn(Handle, OfxTime, OfxTime) -> OfxStatus,
                SpanVariadic,
            >(unsupported_span),
            param_set_value: std::mem::transmute::<
                unsafe extern "C" fn(Handle) -> OfxStatus,
                Variadic,
            >(unsupported),
            param_set_value_at_time: std::mem::transmute::<
                unsafe extern "C" fn(Handle, OfxTime) -> OfxStatus,
                TimedVariadic,
            >(unsupported_timed),
            param_get_num_keys: num_keys,
            param_get_key_time: key_time,
            param_get_key_index: key_index,
            param_delete_key: unsupported_timed,
            param_delete_all_keys: unsupported,
            param_copy: copy,
            param_edit_begin: edit_begin,
            param_edit_end: edit_end,
        }
    }
}
