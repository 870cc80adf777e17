//! The command line's value parsers: each refuses in one line that says
//! what is allowed.

/// A finite number above 0.
pub fn parse_positive(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v > 0.0)
        .ok_or_else(|| format!("{text:?} is not a finite number above 0"))
}

/// A size in pixels, `W` (square) or `WxH`.
pub fn parse_size(text: &str) -> Result<(usize, usize), String> {
    let number = |s: &str| {
        s.trim()
            .parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("{s:?} is not a whole number of pixels above 0 (write W or WxH, e.g. 257 or 511x255)"))
    };
    match text.split_once(['x', 'X']) {
        Some((w, h)) => Ok((number(w)?, number(h)?)),
        None => number(text).map(|n| (n, n)),
    }
}

/// Parses a memory size: a number with an optional unit, K, M, G or T
/// (powers of 1024, with or without `iB`/`B`), e.g. `512M`, `1.5G`, `2GiB`.
pub fn parse_memory(text: &str) -> Result<u64, String> {
    let refuse = |allowed: &str| format!("--max-memory {text:?} is not allowed: {allowed}");
    let trimmed = text.trim();
    let split = trimmed
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(trimmed.len());
    let (number, unit) = trimmed.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| refuse("a number of bytes with an optional unit K, M, G or T, e.g. 4G"))?;
    let shift = match unit.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        _ => return Err(refuse("a unit among K, M, G, T (powers of 1024), e.g. 4G")),
    };
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(refuse("at least 1 byte, e.g. 512M or 4G"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_binary_units() {
        assert_eq!(parse_memory("512M").unwrap(), 512 << 20);
        assert_eq!(parse_memory("1.5G").unwrap(), 3 << 29);
        assert_eq!(parse_memory("2GiB").unwrap(), 2 << 30);
        assert_eq!(parse_memory("1000").unwrap(), 1000);
        for bad in ["", "G", "-1G", "4X", "0"] {
            assert!(parse_memory(bad).is_err(), "{bad}");
        }
    }
}
