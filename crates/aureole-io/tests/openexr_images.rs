//! OpenEXR's own sample and damaged-file set (`../shared/data/openexr-images`,
//! beside the repository; these tests say so and pass when it is absent):
//! every image is read, or refused in one line for a feature we do not
//! handle, and written back with its windows, attributes, parts, layers,
//! channel names and types intact; every damaged file is refused without a
//! crash, in bounded memory.

use std::path::{Path, PathBuf};
use std::time::Instant;

use aureole_io::limits::Limits;
use aureole_io::read::{decode_image, read_image};
use aureole_io::write::{write_linear_into, LinearOptions};
use exr::meta::attribute::SampleType;
use exr::prelude::*;

mod common;
use common::{images, read_all};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files(&path, out);
        } else {
            out.push(path);
        }
    }
}

/// The samples' bits, every NaN as one (a NaN's payload does not survive
/// the f32 planes we spread, and means nothing to a compositor).
fn samples_of(samples: &FlatSamples) -> (SampleType, Vec<u32>) {
    let nan = u32::MAX;
    match samples {
        FlatSamples::F16(v) => (
            SampleType::F16,
            v.iter()
                .map(|h| if h.is_nan() { nan } else { h.to_bits().into() })
                .collect(),
        ),
        FlatSamples::F32(v) => (
            SampleType::F32,
            v.iter()
                .map(|f| if f.is_nan() { nan } else { f.to_bits() })
                .collect(),
        ),
        FlatSamples::U32(v) => (SampleType::U32, v.clone()),
    }
}

/// The refusals we allow: features that are not ours to spread.
fn refused_for_a_reason(message: &str) -> bool {
    message.contains("deep data")
}

/// Whether a file has subsampled channels, which the `exr` crate does not
/// read (tests/luminance_chroma.rs checks them against OpenEXR itself).
fn subsampled(path: &Path) -> bool {
    let meta = exr::meta::MetaData::read_from_file(path, false).unwrap();
    meta.headers
        .iter()
        .flat_map(|h| h.channels.list.iter())
        .any(|c| c.sampling != Vec2(1, 1))
}

#[test]
fn every_sample_image_is_read_or_refused_and_written_back_intact() {
    let Some(dir) = images() else { return };
    let mut all = Vec::new();
    files(&dir, &mut all);
    all.retain(|p| {
        p.extension().is_some_and(|e| e == "exr")
            && !p.components().any(|c| c.as_os_str() == "Damaged")
    });
    all.sort();
    assert!(all.len() > 50, "{} images", all.len());
    let out = tempfile::tempdir().unwrap();
    let (mut read_back, mut refused, mut chroma) = (0, 0, 0);
    for path in &all {
        let loaded = match read_image(path, Limits::NONE) {
            Ok(loaded) => loaded,
            Err(e) => {
                let message = e.to_string();
                assert!(!message.contains('\n'), "{message}");
                assert!(
                    refused_for_a_reason(&message),
                    "{}: {message}",
                    path.display()
                );
                refused += 1;
                continue;
            }
        };
        let written = out.path().join("back.exr");
        write_linear_into(
            &written,
            &loaded.image,
            LinearOptions::default(),
            loaded.original,
        )
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        if subsampled(path) {
            // Luminance and chroma come back as R, G, B at full resolution.
            let after = read_all(&written);
            let names: Vec<String> = after.layer_data[0]
                .channel_data
                .list
                .iter()
                .map(|c| c.name.to_string())
                .collect();
            assert_eq!(names, ["B", "G", "R"], "{}", path.display());
            chroma += 1;
            read_back += 1;
            continue;
        }
        let (before, after) = (read_all(path), read_all(&written));
        let name = path.display();
        assert_eq!(
            before.attributes, after.attributes,
            "{name}: image attributes"
        );
        assert_eq!(
            before.layer_data.len(),
            after.layer_data.len(),
            "{name}: parts"
        );
        for (a, b) in before.layer_data.iter().zip(&after.layer_data) {
            let mut attributes = a.attributes.clone();
            attributes.preview = None;
            assert_eq!(attributes, b.attributes, "{name}: layer attributes");
            assert_eq!(a.size, b.size, "{name}: data window size");
            assert_eq!(
                a.encoding.compression, b.encoding.compression,
                "{name}: compression"
            );
            assert_eq!(
                a.encoding.line_order, b.encoding.line_order,
                "{name}: line order"
            );
            assert_eq!(a.encoding.blocks, b.encoding.blocks, "{name}: blocks");
            let channels = |l: &Layer<AnyChannels<FlatSamples>>| -> Vec<(String, SampleType)> {
                l.channel_data
                    .list
                    .iter()
                    .map(|c| (c.name.to_string(), samples_of(&c.sample_data).0))
                    .collect()
            };
            assert_eq!(channels(a), channels(b), "{name}: channels");
            // Lossy compressions re-encode decoded samples into other ones.
            let lossless = matches!(
                a.encoding.compression,
                Compression::Uncompressed
                    | Compression::RLE
                    | Compression::ZIP1
                    | Compression::ZIP16
                    | Compression::PIZ
            );
            if lossless {
                for (ca, cb) in a.channel_data.list.iter().zip(&b.channel_data.list) {
                    let (sa, sb) = (samples_of(&ca.sample_data).1, samples_of(&cb.sample_data).1);
                    let first = sa.iter().zip(&sb).position(|(x, y)| x != y);
                    assert!(
                        first.is_none(),
                        "{name}: samples of {} differ first at {first:?}: {:#x} became {:#x}",
                        ca.name,
                        first.map_or(0, |i| sa[i]),
                        first.map_or(0, |i| sb[i]),
                    );
                }
            }
        }
        read_back += 1;
    }
    eprintln!(
        "{read_back} images written back intact ({chroma} luminance/chroma ones as RGB), {refused} refused for deep data"
    );
    assert_eq!(chroma, 6);
    assert_eq!(read_back + refused, all.len());
    assert!(read_back >= 63, "{read_back}");
}

#[test]
fn every_damaged_file_is_refused_quickly_in_bounded_memory() {
    let Some(dir) = images() else { return };
    let mut all = Vec::new();
    files(&dir.join("Damaged"), &mut all);
    all.retain(|p| p.extension().is_none_or(|e| e != "rst"));
    all.sort();
    assert!(all.len() > 100, "{} files", all.len());
    let limits = Limits {
        max_bytes: 512 << 20,
    };
    let mut slowest = (0.0, PathBuf::new());
    let mut accepted = Vec::new();
    for path in &all {
        let bytes = std::fs::read(path).unwrap();
        let start = Instant::now();
        let outcome = std::panic::catch_unwind(|| decode_image(&bytes, limits));
        let seconds = start.elapsed().as_secs_f64();
        if seconds > slowest.0 {
            slowest = (seconds, path.clone());
        }
        match outcome {
            Ok(Ok(_)) => accepted.push(path.clone()),
            Ok(Err(message)) => assert!(!message.contains('\n'), "{message}"),
            Err(_) => panic!("{}: the reader panicked", path.display()),
        }
    }
    eprintln!(
        "{} damaged files, the slowest {:.3} s ({})",
        all.len(),
        slowest.0,
        slowest.1.display()
    );
    assert!(accepted.is_empty(), "read as if whole: {accepted:?}");
}
