//! The core stays a core: no file formats, plots or terminal in its
//! dependencies or code, no import circles between its modules, and no
//! message that names a command-line flag or command.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::process::Command;

mod modules;

use modules::{code, sources};

/// The core's sources.
fn src() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")
}

#[test]
fn the_core_depends_on_no_format_plot_or_terminal_crate() {
    let output = Command::new(env!("CARGO"))
        .args([
            "tree",
            "-p",
            "aureole",
            "-e",
            "normal",
            "--prefix",
            "none",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let tree = String::from_utf8_lossy(&output.stdout);
    let crates: BTreeSet<&str> = tree
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(crates.contains("rustfft"), "{tree}");
    for forbidden in ["exr", "image", "plotters", "clap", "anyhow", "indicatif"] {
        assert!(
            !crates.contains(forbidden),
            "aureole depends on {forbidden}"
        );
    }
}

#[test]
fn the_core_writes_no_terminal_and_reads_no_system_files() {
    for (path, text) in sources(&src()) {
        let code = code(&text);
        for word in ["println!", "eprintln!", "stdout", "stderr", "/proc/"] {
            assert!(!code.contains(word), "{} uses {word}", path.display());
        }
    }
}

#[test]
fn no_message_names_a_flag_or_a_command() {
    for (path, text) in sources(&src()) {
        let code = code(&text);
        for (n, literal) in code.split('"').enumerate().filter(|(n, _)| n % 2 == 1) {
            let flag = literal
                .split_whitespace()
                .any(|w| w.starts_with("--") && w.len() > 2);
            let command = ["aureole apply", "aureole psf", "aureole presets"]
                .iter()
                .any(|c| literal.contains(c));
            assert!(
                !flag && !command,
                "{} (string {n}): {literal:?}",
                path.display()
            );
        }
    }
}

#[test]
fn the_modules_import_each_other_without_circles() {
    let uses = modules::uses(&src());
    if let Some(circle) = modules::circle(&uses) {
        panic!("import circle: {}", circle.join(" → "));
    }
    assert!(uses.len() > 8, "{uses:?}");
}
