//! A sequence of frames read and written through one [`Spares`]: each
//! frame is decoded into, and encoded from, the memory of the frames before
//! it, and gives what a frame read and written alone gives.

use std::path::Path;

use aureole::{FrameOptions, Image, Layout};
use aureole_io::formats::Samples;
use aureole_io::job;
use aureole_io::limits::Limits;
use aureole_io::read::{read_image, read_image_reusing, Choice};
use aureole_io::spares::Spares;
use aureole_io::write::{write_linear, write_linear_into, LinearOptions};

const HALF: LinearOptions = LinearOptions {
    samples: Some(Samples::Half),
    compression: None,
};

/// Frame `n`: a lamp that moves over a dim plate.
fn frame(n: usize) -> Image {
    let (w, h) = (64, 40);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.05 * n as f32);
    for plane in &mut image.planes {
        plane[(h / 2) * w + 7 * n] = 2e4;
    }
    image
}

/// The frame as the camera would give it back: something else than it.
fn result_of(image: &Image) -> Image {
    let mut result = image.clone();
    for plane in &mut result.planes {
        plane.iter_mut().for_each(|v| *v = *v * 0.5 + 1.0);
    }
    result
}

/// Reads, "applies" and writes frame `n` through `spares`; returns the
/// addresses its planes were decoded into.
fn through(dir: &Path, n: usize, spares: &Spares) -> Vec<usize> {
    let input = dir.join(format!("in.{n}.exr"));
    let loaded = read_image_reusing(&input, Limits::NONE, &Choice::default(), spares).unwrap();
    let at = loaded
        .image
        .planes
        .iter()
        .map(|p| p.as_ptr() as usize)
        .collect();
    let mut input = job::input(&input, loaded, &FrameOptions::default()).unwrap();
    let result = result_of(input.frame.image());
    input.give_back_planes();
    assert_eq!(
        input
            .frame
            .image()
            .planes
            .iter()
            .map(Vec::len)
            .sum::<usize>(),
        0
    );
    let out = dir.join(format!("out.{n}.exr"));
    write_linear_into(&out, &result, HALF, input.original).unwrap();
    at
}

#[test]
fn later_frames_are_decoded_into_the_first_ones_memory_and_give_the_same_bytes() {
    let temp = tempfile::tempdir().unwrap();
    let dir = temp.path();
    for n in 1..=3 {
        write_linear(&dir.join(format!("in.{n}.exr")), &frame(n), HALF).unwrap();
    }
    let spares = Spares::keeping();
    let first = through(dir, 1, &spares);
    let held = spares.held();
    // Three f32 planes, three half planes and the file's bytes.
    assert!(held >= 64 * 40 * (3 * 4 + 3 * 2), "{held} bytes held");
    for n in 2..=3 {
        let at = through(dir, n, &spares);
        for plane in &at {
            assert!(first.contains(plane), "frame {n} decoded into fresh memory");
        }
        // Only the bytes' buffer may grow, to a larger file's size.
        assert!(
            spares.held() < held + 64 * 40 * 2,
            "frame {n} kept a plane more than frame 1: {} bytes, then {held}",
            spares.held()
        );
    }
    for n in 1..=3 {
        let input = dir.join(format!("in.{n}.exr"));
        let alone = dir.join(format!("alone.{n}.exr"));
        let loaded = read_image(&input, Limits::NONE).unwrap();
        let result = result_of(&loaded.image);
        write_linear_into(&alone, &result, HALF, loaded.original).unwrap();
        assert_eq!(
            std::fs::read(dir.join(format!("out.{n}.exr"))).unwrap(),
            std::fs::read(&alone).unwrap(),
            "frame {n}"
        );
    }
}
