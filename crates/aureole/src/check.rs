//! Range checks of parameters, with the one-line error that names the
//! section, the parameter, the value and what is allowed.

use crate::error::{Error, Result};

/// Refuses `value` unless it is finite and `ok` holds, naming the parameter
/// and the allowed range.
pub(crate) fn range(
    section: &str,
    name: &'static str,
    value: f64,
    ok: bool,
    allowed: &'static str,
) -> Result<()> {
    count(section, name, value, value.is_finite() && ok, allowed)
}

/// Refuses a whole-number (or any other) parameter unless `ok` holds.
pub(crate) fn count(
    section: &str,
    name: &'static str,
    value: impl ToString,
    ok: bool,
    allowed: &'static str,
) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::Parameter {
            effect: section.to_string(),
            name,
            value: value.to_string(),
            allowed,
        })
    }
}
