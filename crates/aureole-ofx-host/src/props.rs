//! Property sets and the property suite (`OfxPropertySuiteV1`). Every
//! handle the plugin passes is looked up among the objects the host made,
//! so a stale or made-up handle gets `kOfxStatErrBadHandle`, a missing
//! property `kOfxStatErrUnknown`, a wrong type `kOfxStatErrValue` and an
//! index past its values `kOfxStatErrBadIndex`, never a crash.

use std::collections::HashMap;
use std::ffi::{c_char, c_double, c_int, c_void, CStr, CString};
use std::sync::Mutex;

use aureole_ofx_abi::{self as abi, Handle, OfxStatus};

/// What the host's objects are, to check a handle's kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    PropSet,
    Effect,
    ParamSet,
    Param,
    Clip,
    Memory,
}

/// Every object the host has handed out, by address.
static LIVE: Mutex<Option<HashMap<usize, Kind>>> = Mutex::new(None);

/// Records `object` as live: its address becomes a valid handle.
pub fn register<T>(object: *const T, kind: Kind) {
    let mut live = LIVE.lock().unwrap_or_else(|p| p.into_inner());
    live.get_or_insert_with(HashMap::new)
        .insert(object as usize, kind);
}

/// Forgets `object`: its handle is no longer valid.
pub fn unregister<T>(object: *const T) {
    let mut live = LIVE.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(live) = live.as_mut() {
        live.remove(&(object as usize));
    }
}

/// The object behind `handle` when it is a live one of `kind`.
pub fn live<'a, T>(handle: *const c_void, kind: Kind) -> Option<&'a T> {
    let live = LIVE.lock().unwrap_or_else(|p| p.into_inner());
    let known = live.as_ref()?.get(&(handle as usize)) == Some(&kind);
    // SAFETY: registered objects of `kind` are `T`s the host keeps alive
    // until it unregisters them.
    known.then(|| unsafe { &*handle.cast::<T>() })
}

/// A property's values, of one type.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Strings(Vec<CString>),
    Doubles(Vec<f64>),
    Ints(Vec<c_int>),
    Pointers(Vec<usize>),
}

/// A set of named properties.
#[derive(Debug, Default)]
pub struct PropSet {
    values: Mutex<HashMap<CString, Value>>,
}

impl PropSet {
    /// A new set, registered, on the heap at a stable address.
    pub fn new() -> Box<PropSet> {
        let set = Box::new(PropSet::default());
        register(&*set, Kind::PropSet);
        set
    }

    /// The set's handle.
    pub fn handle(&self) -> Handle {
        (self as *const PropSet).cast_mut().cast()
    }

    pub fn set(&self, name: &CStr, value: Value) {
        self.values
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .insert(name.to_owned(), value);
    }

    pub fn set_str(&self, name: &CStr, value: &str) {
        let value = CString::new(value).unwrap_or_default();
        self.set(name, Value::Strings(vec![value]));
    }

    pub fn get(&self, name: &CStr) -> Option<Value> {
        self.values
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get(name)
            .cloned()
    }

    pub fn string(&self, name: &CStr, index: usize) -> Option<String> {
        match self.get(name)? {
            Value::Strings(v) => v.get(index).map(|s| s.to_string_lossy().into_owned()),
            _ => None,
        }
    }

    pub fn strings(&self, name: &CStr) -> Vec<String> {
        match self.get(name) {
            Some(Value::Strings(v)) => v.iter().map(|s| s.to_string_lossy().into_owned()).collect(),
            _ => Vec::new(),
        }
    }

    pub fn doubles(&self, name: &CStr) -> Vec<f64> {
        match self.get(name) {
            Some(Value::Doubles(v)) => v,
            Some(Value::Ints(v)) => v.into_iter().map(f64::from).collect(),
            _ => Vec::new(),
        }
    }

    pub fn ints(&self, name: &CStr) -> Vec<c_int> {
        match self.get(name) {
            Some(Value::Ints(v)) => v,
            _ => Vec::new(),
        }
    }

    /// Every property's name and values.
    pub fn entries(&self) -> Vec<(String, Value)> {
        self.values
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter()
            .map(|(k, v)| (k.to_string_lossy().into_owned(), v.clone()))
            .collect()
    }

    pub fn pointer(&self, name: &CStr) -> Option<usize> {
        match self.get(name)? {
            Value::Pointers(v) => v.first().copied(),
            _ => None,
        }
    }

    /// Applies `write` to the values of `name`, made of `empty`'s type when
    /// missing, extended to hold `index`.
    fn write(
        &self,
        name: &CStr,
        index: c_int,
        empty: Value,
        write: impl FnOnce(&mut Value, usize) -> OfxStatus,
    ) -> OfxStatus {
        let Ok(index) = usize::try_from(index) else {
            return abi::STAT_ERR_BAD_INDEX;
        };
        let mut values = self.values.lock().unwrap_or_else(|p| p.into_inner());
        let value = values.entry(name.to_owned()).or_insert(empty);
        write(value, index)
    }

    /// Reads value `index` of `name` with `read`.
    fn read(
        &self,
        name: &CStr,
        index: c_int,
        read: impl FnOnce(&Value, usize) -> OfxStatus,
    ) -> OfxStatus {
        let Ok(index) = usize::try_from(index) else {
            return abi::STAT_ERR_BAD_INDEX;
        };
        let values = self.values.lock().unwrap_or_else(|p| p.into_inner());
        match values.get(name) {
            Some(value) => read(value, index),
            None => abi::STAT_ERR_UNKNOWN,
        }
    }
}

impl Drop for PropSet {
    fn drop(&mut self) {
        unregister(self as *const PropSet);
    }
}

/// Puts `value` at `index` of `values`, growing them with `fill`.
fn put<T: Clone>(values: &mut Vec<T>, index: usize, value: T, fill: T) -> OfxStatus {
    if values.len() <= index {
        values.resize(index + 1, fill);
    }
    values[index] = value;
    abi::STAT_OK
}

/// Copies value `index` of `values` to `out`.
///
/// # Safety
/// `out` is null or points to a writable `T`.
unsafe fn take<T: Clone>(values: &[T], index: usize, out: *mut T) -> OfxStatus {
    match (values.get(index), out.is_null()) {
        (_, true) => abi::STAT_ERR_VALUE,
        (None, false) => abi::STAT_ERR_BAD_INDEX,
        (Some(v), false) => {
            // SAFETY: the caller's pointer, checked non-null.
            unsafe { out.write(v.clone()) };
            abi::STAT_OK
        }
    }
}

/// The set behind `handle` and the property's name, or the status that
/// says which is wrong.
///
/// # Safety
/// `name` is null or a C string.
unsafe fn target<'a>(
    handle: Handle,
    name: *const c_char,
) -> Result<(&'a PropSet, &'a CStr), OfxStatus> {
    let set = live::<PropSet>(handle, Kind::PropSet).ok_or(abi::STAT_ERR_BAD_HANDLE)?;
    if name.is_null() {
        return Err(abi::STAT_ERR_UNKNOWN);
    }
    // SAFETY: the caller's C string.
    Ok((set, unsafe { CStr::from_ptr(name) }))
}

macro_rules! setter {
    ($fn:ident, $ty:ty, $variant:ident, $convert:expr, $fill:expr) => {
        unsafe extern "C" fn $fn(
            h: Handle,
            name: *const c_char,
            index: c_int,
            value: $ty,
        ) -> OfxStatus {
            // SAFETY: the plugin passes a C string name.
            let (set, name) = match unsafe { target(h, name) } {
                Ok(t) => t,
                Err(status) => return status,
            };
            // SAFETY: for strings, the plugin passes a C string.
            let value = match unsafe { $convert(value) } {
                Some(v) => v,
                None => return abi::STAT_ERR_VALUE,
            };
            set.write(name, index, Value::$variant(Vec::new()), |v, i| match v {
                Value::$variant(values) => put(values, i, value, $fill),
                _ => abi::STAT_ERR_VALUE,
            })
        }
    };
}

unsafe fn same<T>(value: T) -> Option<T> {
    Some(value)
}

unsafe fn string_of(value: *const c_char) -> Option<CString> {
    // SAFETY: a non-null C string from the plugin.
    (!value.is_null()).then(|| unsafe { CStr::from_ptr(value) }.to_owned())
}

unsafe fn address(value: *mut c_void) -> Option<usize> {
    Some(value as usize)
}

setter!(set_pointer, *mut c_void, Pointers, address, 0);
setter!(
    set_string,
    *const c_char,
    Strings,
    string_of,
    CString::default()
);
setter!(set_double, c_double, Doubles, same, 0.0);
setter!(set_int, c_int, Ints, same, 0);

macro_rules! getter {
    ($fn:ident, $ty:ty, $variant:ident, $map:expr) => {
        unsafe extern "C" fn $fn(
            h: Handle,
            name: *const c_char,
            index: c_int,
            out: *mut $ty,
        ) -> OfxStatus {
            // SAFETY: the plugin passes a C string name.
            let (set, name) = match unsafe { target(h, name) } {
                Ok(t) => t,
                Err(status) => return status,
            };
            set.read(name, index, |v, i| match v {
                // SAFETY: the plugin's out pointer, checked by `take`.
                Value::$variant(values) => unsafe { take(&$map(values), i, out) },
                _ => abi::STAT_ERR_VALUE,
            })
        }
    };
}

fn pointers(values: &[usize]) -> Vec<*mut c_void> {
    values.iter().map(|&v| v as *mut c_void).collect()
}

/// The stored strings' addresses: valid while the property keeps its value.
fn chars(values: &[CString]) -> Vec<*mut c_char> {
    values.iter().map(|s| s.as_ptr().cast_mut()).collect()
}

fn copied<T: Clone>(values: &[T]) -> Vec<T> {
    values.to_vec()
}

getter!(get_pointer, *mut c_void, Pointers, pointers);
getter!(get_double, c_double, Doubles, copied);
getter!(get_int, c_int, Ints, copied);

/// Strings are handed out as the addresses the set keeps: the set's lock is
/// released at once, and the string lives until the property changes.
unsafe extern "C" fn get_string(
    h: Handle,
    name: *const c_char,
    index: c_int,
    out: *mut *mut c_char,
) -> OfxStatus {
    // SAFETY: the plugin passes a C string name.
    let (set, name) = match unsafe { target(h, name) } {
        Ok(t) => t,
        Err(status) => return status,
    };
    let values = set.values.lock().unwrap_or_else(|p| p.into_inner());
    match (values.get(name), usize::try_from(index)) {
        (None, _) => abi::STAT_ERR_UNKNOWN,
        (_, Err(_)) => abi::STAT_ERR_BAD_INDEX,
        // SAFETY: the plugin's out pointer, checked by `take`.
        (Some(Value::Strings(v)), Ok(i)) => unsafe { take(&chars(v), i, out) },
        (Some(_), Ok(_)) => abi::STAT_ERR_VALUE,
    }
}

macro_rules! many {
    ($fn:ident, $single:ident, $ty:ty, const) => {
        unsafe extern "C" fn $fn(
            h: Handle,
            name: *const c_char,
            count: c_int,
            values: *const $ty,
        ) -> OfxStatus {
            if values.is_null() {
                return abi::STAT_ERR_VALUE;
            }
            for i in 0..count.max(0) {
                // SAFETY: the plugin passes `count` values.
                let status = unsafe { $single(h, name, i, *values.add(i as usize)) };
                if status != abi::STAT_OK {
                    return status;
                }
            }
            abi::STAT_OK
        }
    };
    ($fn:ident, $single:ident, $ty:ty, mut) => {
        unsafe extern "C" fn $fn(
            h: Handle,
            name: *const c_char,
            count: c_int,
            values: *mut $ty,
        ) -> OfxStatus {
            if values.is_null() {
                return abi::STAT_ERR_VALUE;
            }
            for i in 0..count.max(0) {
                // SAFETY: the plugin has room for `count` values.
                let status = unsafe { $single(h, name, i, values.add(i as usize)) };
                if status != abi::STAT_OK {
                    return status;
                }
            }
            abi::STAT_OK
        }
    };
}

many!(set_pointer_n, set_pointer, *mut c_void, const);
many!(set_string_n, set_string, *const c_char, const);
many!(set_double_n, set_double, c_double, const);
many!(set_int_n, set_int, c_int, const);
many!(get_pointer_n, get_pointer, *mut c_void, mut);
many!(get_string_n, get_string, *mut c_char, mut);
many!(get_double_n, get_double, c_double, mut);
many!(get_int_n, get_int, c_int, mut);

unsafe extern "C" fn reset(h: Handle, name: *const c_char) -> OfxStatus {
    // SAFETY: the plugin passes a C string name.
    match unsafe { target(h, name) } {
        Ok((set, name)) => match set.get(name) {
            Some(_) => abi::STAT_OK,
            None => abi::STAT_ERR_UNKNOWN,
        },
        Err(status) => status,
    }
}

unsafe extern "C" fn dimension(h: Handle, name: *const c_char, count: *mut c_int) -> OfxStatus {
    // SAFETY: the plugin passes a C string name.
    let (set, name) = match unsafe { target(h, name) } {
        Ok(t) => t,
        Err(status) => return status,
    };
    let n = match set.get(name) {
        Some(Value::Strings(v)) => v.len(),
        Some(Value::Doubles(v)) => v.len(),
        Some(Value::Ints(v)) => v.len(),
        Some(Value::Pointers(v)) => v.len(),
        None => return abi::STAT_ERR_UNKNOWN,
    };
    if count.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    // SAFETY: the plugin's pointer, checked non-null.
    unsafe { count.write(n as c_int) };
    abi::STAT_OK
}

/// The property suite the host hands out.
pub static SUITE: abi::OfxPropertySuiteV1 = abi::OfxPropertySuiteV1 {
    prop_set_pointer: set_pointer,
    prop_set_string: set_string,
    prop_set_double: set_double,
    prop_set_int: set_int,
    prop_set_pointer_n: set_pointer_n,
    prop_set_string_n: set_string_n,
    prop_set_double_n: set_double_n,
    prop_set_int_n: set_int_n,
    prop_get_pointer: get_pointer,
    prop_get_string: get_string,
    prop_get_double: get_double,
    prop_get_int: get_int,
    prop_get_pointer_n: get_pointer_n,
    prop_get_string_n: get_string_n,
    prop_get_double_n: get_double_n,
    prop_get_int_n: get_int_n,
    prop_reset: reset,
    prop_get_dimension: dimension,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn properties_answer_with_the_specifications_statuses() {
        let set = PropSet::new();
        let h = set.handle();
        let (mut i, mut d, mut s) = (0, 0.0, std::ptr::null_mut());
        // SAFETY: the suite's own functions, as a plugin calls them.
        unsafe {
            assert_eq!((SUITE.prop_set_int)(h, c"a".as_ptr(), 1, 5), abi::STAT_OK);
            assert_eq!(
                (SUITE.prop_get_int)(h, c"a".as_ptr(), 1, &mut i),
                abi::STAT_OK
            );
            assert_eq!(i, 5);
            let mut n = 0;
            assert_eq!(
                (SUITE.prop_get_dimension)(h, c"a".as_ptr(), &mut n),
                abi::STAT_OK
            );
            assert_eq!(n, 2);
            assert_eq!(
                (SUITE.prop_get_int)(h, c"a".as_ptr(), 2, &mut i),
                abi::STAT_ERR_BAD_INDEX
            );
            assert_eq!(
                (SUITE.prop_get_int)(h, c"a".as_ptr(), -1, &mut i),
                abi::STAT_ERR_BAD_INDEX
            );
            assert_eq!(
                (SUITE.prop_get_double)(h, c"a".as_ptr(), 0, &mut d),
                abi::STAT_ERR_VALUE
            );
            assert_eq!(
                (SUITE.prop_set_double)(h, c"a".as_ptr(), 0, 1.0),
                abi::STAT_ERR_VALUE
            );
            assert_eq!(
                (SUITE.prop_get_string)(h, c"b".as_ptr(), 0, &mut s),
                abi::STAT_ERR_UNKNOWN
            );
            assert_eq!(
                (SUITE.prop_set_string)(h, c"b".as_ptr(), 0, c"x".as_ptr()),
                abi::STAT_OK
            );
            assert_eq!(
                (SUITE.prop_get_string)(h, c"b".as_ptr(), 0, &mut s),
                abi::STAT_OK
            );
            assert_eq!(CStr::from_ptr(s), c"x");
            assert_eq!(
                (SUITE.prop_get_int)(h, std::ptr::null(), 0, &mut i),
                abi::STAT_ERR_UNKNOWN
            );
            assert_eq!(
                (SUITE.prop_get_int)(h, c"a".as_ptr(), 0, std::ptr::null_mut()),
                abi::STAT_ERR_VALUE
            );
            let made_up = 0x10usize as Handle;
            assert_eq!(
                (SUITE.prop_get_int)(made_up, c"a".as_ptr(), 0, &mut i),
                abi::STAT_ERR_BAD_HANDLE
            );
        }
        drop(set);
        // SAFETY: a handle the host no longer knows is refused, not read.
        unsafe {
            assert_eq!(
                (SUITE.prop_get_int)(h, c"a".as_ptr(), 0, &mut i),
                abi::STAT_ERR_BAD_HANDLE
            );
        }
    }
}
