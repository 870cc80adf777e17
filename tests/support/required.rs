//! A test whose reference is missing here (a tool, a library, a sample
//! image, a GPU): where CI runs (`CI` set, as `.ci/run` is started) that is
//! a failure naming it, since CI installs every reference; elsewhere the
//! test skips, and says so where it is seen: `scripts/test` lists every
//! skip at its end (the file `AUREOLE_SKIPS` names), since `cargo test`
//! hides what a passing test prints. Each test binary that needs it
//! includes this file (`#[path]`): the crates' tests share no crate.

#![allow(dead_code)]

use std::io::Write;

/// Whether this run is CI's: `CI` set to anything but empty, `0` or
/// `false`.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0" && v != "false")
}

/// Whether this process runs as root, who reads and writes whatever the
/// permissions say: a test of them runs again as `nobody` (setpriv).
pub fn running_as_root() -> bool {
    std::process::Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// `test` cannot run here because `what` is missing (with how to get
/// it): panics under CI, else records the skip and returns, for the test
/// to return too.
pub fn missing(test: &str, what: &str) {
    assert!(
        !in_ci(),
        "{test}: {what}; CI installs it (.ci/run), so its absence there is a failure"
    );
    eprintln!("{test}: skipped: {what}");
    if let Some(path) = std::env::var_os("AUREOLE_SKIPS") {
        if let Ok(mut file) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
        {
            let _ = writeln!(file, "{test}: {what}");
        }
    }
}
