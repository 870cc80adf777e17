//! The command lines that do what an export does: the page asks for them
//! (`POST /api/command`) instead of building them, so that they follow the
//! command line's flags and the export's rules in one place.

use serde::Serialize;

use crate::error::StudioError;
use crate::export::ExportRequest;
use crate::render::{display_options, max_extent, View, DEMO};
use aureole_io::display::{Exposure, ToneCurve};

/// The name the page gives the camera's TOML when it downloads it.
pub const CONFIG_FILE: &str = "camera.toml";

/// What the page shows: each command's arguments, and the lines to paste
/// into a POSIX shell.
#[derive(Debug, Serialize)]
pub struct Commands {
    /// Each command as its arguments, `aureole` first.
    pub argv: Vec<Vec<String>>,
    /// The commands, one per line, quoted for a shell.
    pub text: String,
}

/// The commands that write what `request` exports, its camera read from
/// [`CONFIG_FILE`]; the demo scene is written first as `street.exr`.
pub fn for_export(request: &ExportRequest) -> Result<Commands, StudioError> {
    let render = &request.render;
    let display = display_options(render)?;
    // A command the command line would refuse is not offered.
    aureole_io::job::Request {
        output: std::path::Path::new(&request.output),
        input: None,
        options: &render.options()?,
        layers: request.layers,
    }
    .check_asked()
    .map_err(|e| StudioError::BadRequest(e.to_string()))?;
    let mut argv = Vec::new();
    let image = if render.image == DEMO {
        argv.push(words(&[
            "aureole",
            "demo",
            "--hdr",
            "street.exr",
            "-o",
            "street.png",
        ]));
        "street.exr"
    } else {
        render.image.as_str()
    };
    let mut apply = words(&["aureole", "apply", image, "--config", CONFIG_FILE]);
    if let Some(threshold) = render.threshold {
        apply.extend(words(&["--threshold", &threshold.to_string()]));
    }
    if render.knee != 0.0 {
        apply.extend(words(&["--knee", &render.knee.to_string()]));
    }
    match display.exposure {
        Exposure::Auto => {}
        Exposure::Ev(ev) => apply.extend(words(&["--exposure", &ev.to_string()])),
        Exposure::White(white) => apply.extend(words(&["--white", &white.to_string()])),
    }
    if display.tone != ToneCurve::Filmic {
        apply.extend(words(&["--tonemap", display.tone.name()]));
    }
    if render.view == View::Glare {
        apply.push("--glare-only".into());
    }
    if request.layers {
        apply.push("--layers".into());
    }
    if let Some((width, height)) = max_extent(render)? {
        apply.extend(words(&["--max-kernel", &format!("{width}x{height}")]));
    }
    apply.extend(words(&["-o", &request.output]));
    argv.push(apply);
    let text = argv
        .iter()
        .map(|command| {
            command
                .iter()
                .map(|w| quoted(w))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n");
    Ok(Commands { argv, text })
}

fn words(list: &[&str]) -> Vec<String> {
    list.iter().map(|w| w.to_string()).collect()
}

/// `word` as a POSIX shell reads it back: as it is when it holds nothing a
/// shell would change, else in single quotes.
fn quoted(word: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "._/-=:,+%@".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_a_shell_would_change_are_quoted() {
        assert_eq!(quoted("shot.0001.exr"), "shot.0001.exr");
        assert_eq!(quoted("my shot.exr"), "'my shot.exr'");
        assert_eq!(quoted("it's.exr"), r"'it'\''s.exr'");
        assert_eq!(quoted("$HOME"), "'$HOME'");
        assert_eq!(quoted(""), "''");
    }
}
