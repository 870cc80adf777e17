//! Renders an image file through an OpenFX bundle in the test host, as a
//! compositor renders a sequence: one instance, a sequence of frames, the
//! time of each render printed as JSON (the first builds the kernel).
//!
//!   ofx-render BUNDLE INPUT.exr --preset NAME [--frames N] [-o OUTPUT.exr]

use std::path::PathBuf;
use std::time::Instant;

use aureole_ofx_abi::names;
use aureole_ofx_host::{Picture, Plugin, Project, Setting};

fn main() {
    if let Err(error) = run() {
        eprintln!("ofx-render: {error}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let (mut positional, mut preset, mut frames, mut output) = (Vec::new(), None, 3usize, None);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--preset" => preset = args.next(),
            "--frames" => {
                frames = args
                    .next()
                    .and_then(|n| n.parse().ok())
                    .ok_or("--frames N")?
            }
            "-o" => output = args.next().map(PathBuf::from),
            _ => positional.push(PathBuf::from(arg)),
        }
    }
    let [bundle, input] = <[PathBuf; 2]>::try_from(positional)
        .map_err(|_| "usage: ofx-render BUNDLE INPUT --preset NAME [--frames N] [-o OUTPUT]")?;
    let preset = preset.ok_or("--preset NAME is needed")?;
    let limits = aureole_io::limits::Limits::default_for_machine();
    let image = aureole_io::read::read_image(&input, limits)
        .map_err(|e| e.to_string())?
        .image;
    let (w, h) = (image.width, image.height);
    let source = Picture::of_image(&image, 4);

    let plugin = Plugin::load(&bundle).map_err(|e| e.to_string())?;
    plugin.describe().map_err(|e| e.to_string())?;
    plugin
        .describe_in_context(names::CONTEXT_FILTER)
        .map_err(|e| e.to_string())?;
    let choice = |name: &str, option: &str| -> Result<Setting, String> {
        let menu = plugin
            .param_definition(names::CONTEXT_FILTER, name)
            .ok_or(format!("no parameter {name}"))?
            .strings(names::PARAM_CHOICE_OPTION);
        let at = menu
            .iter()
            .position(|o| o == option)
            .ok_or(format!("{name}: no {option}"))?;
        Ok(Setting::Int(at as i32))
    };
    let instance = plugin
        .instance(names::CONTEXT_FILTER, Project::of(w, h))
        .map_err(|e| e.to_string())?;
    instance
        .set("preset", choice("preset", &preset)?)
        .map_err(|e| e.to_string())?;
    instance
        .set("device", choice("device", "cpu")?)
        .map_err(|e| e.to_string())?;
    let last = frames as f64;
    instance
        .begin_sequence(1.0, last, [1.0, 1.0])
        .map_err(|e| e.to_string())?;
    let mut times = Vec::new();
    // The host's two buffers, reused from frame to frame as a host's
    // image cache does.
    let mut buffers = (source.clone(), source);
    for frame in 1..=frames {
        let start = Instant::now();
        buffers = instance
            .render_buffers(frame as f64, buffers.0, buffers.1, [1.0, 1.0])
            .map_err(|e| e.to_string())?;
        times.push(start.elapsed().as_secs_f64());
    }
    let rendered = Some(buffers.1);
    instance
        .end_sequence(1.0, last, [1.0, 1.0])
        .map_err(|e| e.to_string())?;
    if let (Some(path), Some(picture)) = (output, rendered) {
        let mut result = image.clone();
        for (plane, rendered) in result.planes.iter_mut().zip(picture.to_image().planes) {
            *plane = rendered;
        }
        aureole_io::write::write_linear(&path, &result, Default::default())
            .map_err(|e| e.to_string())?;
    }
    let list: Vec<String> = times.iter().map(|t| format!("{t:.4}")).collect();
    println!(
        "{{\"width\": {w}, \"height\": {h}, \"frames\": [{}]}}",
        list.join(", ")
    );
    Ok(())
}
