//! How much memory a decoder may take, and how much this machine can give:
//! the default limit front ends hand to the library.

/// Bounds on what a decoder may allocate, checked against the dimensions a
/// file declares before any pixel is decoded (a header is untrusted input).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// The most bytes the decoded image and the decoder's own buffers may take.
    pub max_bytes: u64,
}

impl Limits {
    /// No bound but the address space.
    pub const NONE: Limits = Limits {
        max_bytes: u64::MAX,
    };
}

/// The memory the system can give now (Linux: `MemAvailable` of
/// /proc/meminfo), if known.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

impl Limits {
    /// [`default_memory_limit`] as a decoder's bound.
    pub fn default_for_machine() -> Limits {
        Limits {
            max_bytes: default_memory_limit(),
        }
    }
}

/// The default memory limit: three quarters of what the system can give
/// now (leaving room for the rest of the machine), or 8 GiB where that is
/// unknown.
pub fn default_memory_limit() -> u64 {
    available_memory().map_or(8 << 30, |bytes| bytes / 4 * 3)
}
