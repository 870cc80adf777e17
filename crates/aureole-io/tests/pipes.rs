//! Images that are not regular files: a device is refused before a byte is
//! read, a pipe is read once (no look at its header takes bytes from it)
//! and only up to the memory limit.

#![cfg(unix)]

use std::io::Write;
use std::path::Path;

use aureole::{Image, Layout};
use aureole_io::formats::Choice;
use aureole_io::limits::Limits;
use aureole_io::read::{probe, read_image};
use aureole_io::write::{write_linear, LinearOptions};

fn fifo(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("pipe.exr");
    let made = std::process::Command::new("mkfifo")
        .arg(&path)
        .status()
        .unwrap();
    assert!(made.success());
    path
}

/// Writes `bytes` into the pipe at `path` on a thread, as another program
/// would; a reader that stops early leaves it a broken pipe, not a hang.
fn feed(path: &Path, bytes: Vec<u8>) -> std::thread::JoinHandle<()> {
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        if let Ok(mut pipe) = std::fs::OpenOptions::new().write(true).open(path) {
            let _ = pipe.write_all(&bytes);
        }
    })
}

#[test]
fn a_device_is_refused_before_it_is_read() {
    let refused = read_image(Path::new("/dev/zero"), Limits::NONE)
        .unwrap_err()
        .to_string();
    assert_eq!(
        refused,
        "/dev/zero: is a device, not an image file; read a file, or a pipe (a named pipe, /dev/stdin)"
    );
}

#[test]
fn an_exr_through_a_pipe_is_read_once_whole() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("frame.exr");
    let mut image = Image::filled(48, 27, Layout::Rgb, 0.25);
    image.planes[1][100] = 4000.0;
    write_linear(&file, &image, LinearOptions::default()).unwrap();
    let pipe = fifo(dir.path());
    let writer = feed(&pipe, std::fs::read(&file).unwrap());
    // The header is not looked at: that would take the bytes the reader
    // needs (and a second open would wait for a writer that is gone).
    assert_eq!(
        probe(&pipe, Limits::NONE, &Choice::default()).unwrap(),
        None
    );
    let read = read_image(&pipe, Limits::NONE).unwrap();
    writer.join().unwrap();
    assert_eq!(read.image.planes, image.planes);
}

#[test]
fn a_pipe_beyond_the_memory_limit_is_refused_after_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let pipe = fifo(dir.path());
    let writer = feed(&pipe, vec![0u8; 3 << 20]);
    let limits = Limits { max_bytes: 1 << 20 };
    let refused = read_image(&pipe, limits).unwrap_err().to_string();
    drop(writer);
    assert!(
        refused.ends_with("holds more than the memory limit (1.0 MiB) allows to read"),
        "{refused}"
    );
}
