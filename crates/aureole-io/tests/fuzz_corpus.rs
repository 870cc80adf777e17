//! Replays what the fuzzers (`fuzz/`) found and grew: every corpus input
//! and every crash reproducer must give an image or an error, never a
//! panic. Runs in the normal test suite, without cargo-fuzz.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn inputs(target: &str) -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut files = Vec::new();
    for kind in ["corpus", "regressions"] {
        if let Ok(entries) = std::fs::read_dir(root.join(kind).join(target)) {
            files.extend(entries.filter_map(|e| e.ok()).map(|e| e.path()));
        }
    }
    files.sort();
    files
}

/// Runs `entry` on every input of `target`; reports the slowest (a hang
/// shows as a test that never ends, and the slowest is named to find it).
fn replay(target: &str, entry: fn(&[u8])) {
    let files = inputs(target);
    assert!(!files.is_empty(), "no corpus for {target}");
    let mut slowest = (Duration::ZERO, PathBuf::new());
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        let start = Instant::now();
        entry(&bytes);
        let took = start.elapsed();
        if took > slowest.0 {
            slowest = (took, path.clone());
        }
    }
    eprintln!(
        "{target}: {} inputs, slowest {:?} ({})",
        files.len(),
        slowest.0,
        slowest.1.display()
    );
}

#[test]
fn config_corpus_parses_or_refuses() {
    replay("config", aureole_io::fuzzing::config);
}

#[test]
fn pfm_corpus_decodes_or_refuses() {
    replay("pfm", aureole_io::fuzzing::pfm);
}

#[test]
fn load_corpus_decodes_or_refuses() {
    replay("load", aureole_io::fuzzing::load);
}
