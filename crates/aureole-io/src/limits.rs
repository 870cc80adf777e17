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

/// The memory the system can give now, if known (Linux): `MemAvailable`
/// of /proc/meminfo, or less where the process's control group (a
/// container's, a farm job's) has less room below its limit: there the
/// kernel kills a process at its group's limit, whatever the machine has
/// free.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    let machine = kib * 1024;
    let membership = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    let group = group_room(&membership, std::path::Path::new("/sys/fs/cgroup"));
    let read = |path| std::fs::read_to_string(path).unwrap_or_default();
    let space = address_room(&read("/proc/self/limits"), &read("/proc/self/status"));
    Some([group, space].into_iter().flatten().fold(machine, u64::min))
}

/// The room below the process's address-space limit (`ulimit -v`, which
/// some farms set): its soft limit in /proc/self/limits less the
/// `VmSize` of /proc/self/status. Beyond it an allocation fails, which
/// aborts the run. `None` where unlimited.
fn address_room(limits: &str, status: &str) -> Option<u64> {
    let limit: u64 = limits
        .lines()
        .find_map(|l| l.strip_prefix("Max address space"))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let size_kib: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmSize:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .unwrap_or(0);
    Some(limit.saturating_sub(size_kib * 1024))
}

/// A limit this large means none (cgroup v1 writes 2⁶³ rounded to pages).
const UNLIMITED: u64 = 1 << 62;

/// The room below the memory limit of the control group `membership`
/// (/proc/self/cgroup's text) names, under the cgroup file system at
/// `root`: the least over the group's own folder and the mount's root (a
/// container sees its own group there), for cgroup v2 (`memory.max`,
/// `memory.current`) and v1 (`memory/memory.limit_in_bytes`,
/// `usage_in_bytes`). Inactive file pages are counted as room: the kernel
/// drops them before it kills. `None` where no limit is set.
fn group_room(membership: &str, root: &std::path::Path) -> Option<u64> {
    let read = |path: std::path::PathBuf| std::fs::read_to_string(path).ok();
    let number = |text: Option<String>| text.and_then(|t| t.trim().parse::<u64>().ok());
    let inactive = |stat: Option<String>, key: &str| {
        stat.and_then(|text| {
            text.lines().find_map(|l| {
                l.strip_prefix(key)
                    .and_then(|v| v.trim().parse::<u64>().ok())
            })
        })
        .unwrap_or(0)
    };
    // Per version: the limit, the usage and memory.stat's key of the
    // inactive file pages, each in the group's folder.
    const V2: [&str; 3] = ["memory.max", "memory.current", "inactive_file "];
    const V1: [&str; 3] = [
        "memory.limit_in_bytes",
        "memory.usage_in_bytes",
        "total_inactive_file ",
    ];
    let mut folders = Vec::new();
    for line in membership.lines() {
        let mut fields = line.splitn(3, ':');
        let (_, controllers, path) = (fields.next(), fields.next(), fields.next());
        let Some(path) = path.map(|p| p.trim_start_matches('/')) else {
            continue;
        };
        match controllers {
            Some("") => folders.push((root.join(path), V2)),
            Some(list) if list.split(',').any(|c| c == "memory") => {
                folders.push((root.join("memory").join(path), V1));
            }
            _ => {}
        }
    }
    folders.push((root.to_path_buf(), V2));
    folders.push((root.join("memory"), V1));
    folders
        .into_iter()
        .filter_map(|(folder, [limit, usage, key])| {
            let limit = number(read(folder.join(limit))).filter(|&l| l < UNLIMITED)?;
            let busy = inactive(read(folder.join("memory.stat")), key);
            let used = number(read(folder.join(usage)))?.saturating_sub(busy);
            Some(limit.saturating_sub(used))
        })
        .min()
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

#[cfg(test)]
mod tests {
    use super::*;

    fn write(root: &std::path::Path, file: &str, text: &str) {
        let path = root.join(file);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }

    #[test]
    fn an_address_space_limit_bounds_the_room_less_what_is_mapped() {
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         8589934592           unlimited            bytes\n";
        let status = "Name:\taureole\nVmSize:\t  1048576 kB\n";
        assert_eq!(address_room(limits, status), Some(7 << 30));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_room(unlimited, status), None);
        assert_eq!(address_room("", status), None);
    }

    #[test]
    fn a_control_groups_limit_bounds_the_room_less_its_busy_pages() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        // cgroup v2: a job's group with 4 GiB, 3 GiB used of which 1 GiB
        // inactive file pages.
        write(root, "farm/job/memory.max", "4294967296\n");
        write(root, "farm/job/memory.current", "3221225472\n");
        write(
            root,
            "farm/job/memory.stat",
            "anon 2147483648\ninactive_file 1073741824\n",
        );
        assert_eq!(group_room("0::/farm/job\n", root), Some(2 << 30));
        // Without a limit: none; "max" is none either.
        write(root, "farm/job/memory.max", "max\n");
        assert_eq!(group_room("0::/farm/job\n", root), None);
        // cgroup v1, as Docker mounts it: the container's group at the
        // controller's root, the unlimited host group named in the file.
        write(root, "memory/memory.limit_in_bytes", "8589934592\n");
        write(root, "memory/memory.usage_in_bytes", "1073741824\n");
        write(
            root,
            "memory/memory.stat",
            "cache 0\ntotal_inactive_file 0\n",
        );
        write(
            root,
            "memory/docker/abc/memory.limit_in_bytes",
            "9223372036854771712\n",
        );
        let v1 = "4:memory:/docker/abc\n0::/\n";
        assert_eq!(group_room(v1, root), Some(7 << 30));
        // Nothing there: nothing known.
        let empty = tempfile::tempdir().unwrap();
        assert_eq!(group_room("0::/\n", empty.path()), None);
    }
}
