//! Which files a run reads and writes: one input, a list, or a numbered
//! frame pattern (`shot.%04d.exr` with `--frames 1-240`).

use std::path::{Path, PathBuf};

use anyhow::anyhow;

use crate::Failure;

/// One input and where its result goes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pair {
    pub input: PathBuf,
    pub output: PathBuf,
}

/// The most frames a list may name: a typo such as 1-10000000 should be
/// refused, not expanded.
const MAX_FRAMES: u64 = 1_000_000;

/// Frame numbers, in the order given, each once.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frames(pub Vec<u64>);

/// Parses a frame list: `1-240`, `7`, `1-10,20,30-40`, in that order; a
/// frame named twice is done once.
pub fn parse_frames(text: &str) -> Result<Frames, String> {
    let bad = |part: &str| {
        format!("{part:?} is not a frame number or range; write e.g. 1-240 or 1-10,20,30-40")
    };
    let mut frames = Vec::new();
    for part in text.split(',') {
        let number = |s: &str| s.trim().parse::<u64>().map_err(|_| bad(part));
        let (first, last) = match part.split_once('-') {
            Some((a, b)) => (number(a)?, number(b)?),
            None => (number(part)?, number(part)?),
        };
        if last < first {
            return Err(format!(
                "{part:?} runs backwards; write the first frame first"
            ));
        }
        if (last - first).saturating_add(1) > MAX_FRAMES - frames.len() as u64 {
            return Err(format!("{text:?} names more than {MAX_FRAMES} frames"));
        }
        frames.extend(first..=last);
    }
    let mut seen = std::collections::HashSet::new();
    frames.retain(|f| seen.insert(*f));
    Ok(Frames(frames))
}

/// Where the `%d` or `%0Nd` of a pattern is, and its width.
fn placeholder(pattern: &str) -> Option<(usize, usize, usize)> {
    let start = pattern.find('%')?;
    let rest = &pattern[start + 1..];
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    if rest.as_bytes().get(digits) != Some(&b'd') {
        return None;
    }
    let width = rest[..digits].parse().unwrap_or(0);
    Some((start, start + 1 + digits + 1, width))
}

/// `pattern` with its placeholder replaced by `frame`.
fn expand(pattern: &Path, frame: u64) -> Option<PathBuf> {
    let text = pattern.to_str()?;
    let (start, end, width) = placeholder(text)?;
    Some(PathBuf::from(format!(
        "{}{frame:0width$}{}",
        &text[..start],
        &text[end..]
    )))
}

fn has_placeholder(path: &Path) -> bool {
    path.to_str().and_then(placeholder).is_some()
}

/// The inputs of a run, each with its output, or a usage error saying why the names do not fit
/// together.
pub fn pairs(
    inputs: &[PathBuf],
    output: &Path,
    frames: Option<&[u64]>,
) -> Result<Vec<Pair>, Failure> {
    let usage = |text: String| Failure::Usage(anyhow!(text));
    let folder = output.is_dir();
    let into_folder = |input: &Path| -> Result<PathBuf, Failure> {
        input
            .file_name()
            .map(|name| output.join(name))
            .ok_or_else(|| usage(format!("{}: names no file", input.display())))
    };
    match frames {
        Some(frames) => {
            let [pattern] = inputs else {
                return Err(usage(
                    "--frames takes one input pattern, such as shot.%04d.exr".into(),
                ));
            };
            if !has_placeholder(pattern) {
                return Err(usage(format!(
                    "{}: --frames needs a %d or %04d in the input name for the frame number",
                    pattern.display()
                )));
            }
            if !folder && !has_placeholder(output) {
                return Err(usage(format!(
                    "{}: with --frames the output must be a folder or a pattern with %d or %04d",
                    output.display()
                )));
            }
            frames
                .iter()
                .map(|&frame| {
                    let input = expand(pattern, frame).unwrap_or_else(|| pattern.clone());
                    let output = match expand(output, frame) {
                        Some(path) => path,
                        None => into_folder(&input)?,
                    };
                    Ok(Pair { input, output })
                })
                .collect()
        }
        None if inputs.iter().chain([&output.to_path_buf()]).any(|p| has_placeholder(p)) => {
            Err(usage(format!(
                "{}: a %d or %04d in a name stands for frame numbers, which --frames gives (e.g. --frames 1-240)",
                inputs
                    .iter()
                    .find(|p| has_placeholder(p))
                    .map_or(output, PathBuf::as_path)
                    .display()
            )))
        }
        None if inputs.len() == 1 && !folder => Ok(vec![Pair {
            input: inputs[0].clone(),
            output: output.to_path_buf(),
        }]),
        None if folder => inputs
            .iter()
            .map(|input| {
                Ok(Pair {
                    input: input.clone(),
                    output: into_folder(input)?,
                })
            })
            .collect(),
        None => Err(usage(format!(
            "{}: with several inputs the output must be an existing folder",
            output.display()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_lists_expand_in_order() {
        assert_eq!(
            parse_frames("1-3,7,9-10").unwrap().0,
            vec![1, 2, 3, 7, 9, 10]
        );
        for bad in [
            "",
            "a-3",
            "5-2",
            "1-",
            "0-99999999",
            "0-18446744073709551615",
            "1-999999,1000001-1000002",
        ] {
            assert!(parse_frames(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_frames("1-3,2,1,5").unwrap().0, vec![1, 2, 3, 5]);
    }

    #[test]
    fn patterns_take_the_frame_number() {
        let path = |s: &str| PathBuf::from(s);
        assert_eq!(expand(&path("s.%04d.exr"), 7), Some(path("s.0007.exr")));
        assert_eq!(expand(&path("s.%d.exr"), 12345), Some(path("s.12345.exr")));
        assert_eq!(expand(&path("s.exr"), 7), None);
        assert_eq!(expand(&path("s.%x.exr"), 7), None);
        let Ok(pairs) = pairs(
            &[path("in/s.%03d.exr")],
            &path("out/o.%03d.png"),
            Some(&[1, 2]),
        ) else {
            panic!("a pattern with frames was refused");
        };
        assert_eq!(pairs[1].input, path("in/s.002.exr"));
        assert_eq!(pairs[1].output, path("out/o.002.png"));
    }
}
