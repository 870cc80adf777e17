//! Lays pictures out side by side, with a caption under each, for the
//! gallery (`scripts/gallery.sh`): the same crop of every panel, scaled to
//! one width, so that a before and an after line up pixel for pixel.
//!
//! ```sh
//! cargo run --release -p aureole-tools --bin montage -- OUT.jpg \
//!     [--columns N] [--width PX] [--crop X,Y,W,H] [--gap PX] [--quality Q] \
//!     PICTURE=CAPTION ...
//! ```
//!
//! `--width` is the width of each panel (default: the crop's own); the
//! output's extension picks JPEG (at `--quality`, default 88) or PNG;
//! `--gap` is the dark margin around and between panels (default 6).

#![deny(unsafe_code)]

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use aureole_io::atomic::write_atomic;
use aureole_io::plot::font_family;
use image::codecs::jpeg::JpegEncoder;
use image::imageops::{self, FilterType};
use image::{ImageFormat, RgbImage};
use plotters::prelude::*;
const BACKGROUND: [u8; 3] = [17, 17, 17];

struct Panel {
    path: PathBuf,
    caption: String,
}

struct Layout {
    output: PathBuf,
    columns: u32,
    width: Option<u32>,
    crop: Option<[u32; 4]>,
    gap: u32,
    quality: u8,
    panels: Vec<Panel>,
}

fn main() -> ExitCode {
    match parse(std::env::args().skip(1)).and_then(|layout| run(&layout)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("montage: error: {message}");
            ExitCode::from(2)
        }
    }
}

fn parse(mut args: impl Iterator<Item = String>) -> Result<Layout, String> {
    let usage = "usage: montage OUT [--columns N] [--width PX] [--crop X,Y,W,H] [--gap PX] [--quality Q] PICTURE=CAPTION ...";
    let output = args.next().ok_or(usage)?.into();
    let mut layout = Layout {
        output,
        columns: 0,
        width: None,
        crop: None,
        gap: 6,
        quality: 88,
        panels: Vec::new(),
    };
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--columns" => layout.columns = number(&value("--columns")?, "--columns")?,
            "--width" => layout.width = Some(number(&value("--width")?, "--width")?),
            "--gap" => layout.gap = number(&value("--gap")?, "--gap")?,
            "--quality" => layout.quality = number(&value("--quality")?, "--quality")?,
            "--crop" => {
                let text = value("--crop")?;
                let parts = text
                    .split(',')
                    .map(|part| number(part, "--crop"))
                    .collect::<Result<Vec<u32>, _>>()?;
                layout.crop = Some(
                    parts
                        .try_into()
                        .map_err(|_| format!("--crop {text}: give X,Y,W,H"))?,
                );
            }
            flag if flag.starts_with("--") => {
                return Err(format!("unknown option {flag}\n{usage}"))
            }
            panel => {
                let (path, caption) = panel.split_once('=').unwrap_or((panel, ""));
                layout.panels.push(Panel {
                    path: path.into(),
                    caption: caption.to_string(),
                });
            }
        }
    }
    if layout.panels.is_empty() {
        return Err(usage.into());
    }
    if layout.columns == 0 {
        layout.columns = layout.panels.len() as u32;
    }
    Ok(layout)
}

fn number<T: std::str::FromStr>(text: &str, name: &str) -> Result<T, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("{name}: `{text}` is not a whole number"))
}

fn load(panel: &Panel, layout: &Layout) -> Result<RgbImage, String> {
    let picture = image::open(&panel.path)
        .map_err(|e| format!("{}: {e}", panel.path.display()))?
        .to_rgb8();
    let picture = match layout.crop {
        Some([x, y, w, h]) => {
            if x + w > picture.width() || y + h > picture.height() || w == 0 || h == 0 {
                return Err(format!(
                    "{}: the crop {x},{y},{w},{h} is not inside its {}x{} pixels",
                    panel.path.display(),
                    picture.width(),
                    picture.height()
                ));
            }
            imageops::crop_imm(&picture, x, y, w, h).to_image()
        }
        None => picture,
    };
    Ok(match layout.width {
        Some(width) if width != picture.width() => {
            let height = (u64::from(picture.height()) * u64::from(width)
                / u64::from(picture.width()))
            .max(1) as u32;
            imageops::resize(&picture, width, height, FilterType::Lanczos3)
        }
        _ => picture,
    })
}

fn run(layout: &Layout) -> Result<(), String> {
    let pictures = layout
        .panels
        .iter()
        .map(|panel| load(panel, layout))
        .collect::<Result<Vec<_>, _>>()?;
    let cell_width = pictures.iter().map(RgbImage::width).max().unwrap_or(1);
    let picture_height = pictures.iter().map(RgbImage::height).max().unwrap_or(1);
    let captioned = layout.panels.iter().any(|panel| !panel.caption.is_empty());
    let font_size = (cell_width / 24).clamp(12, 22);
    let caption_height = if captioned { font_size * 2 } else { 0 };
    let cell_height = picture_height + caption_height;
    let columns = layout.columns.min(pictures.len() as u32);
    let rows = (pictures.len() as u32).div_ceil(columns);
    let gap = layout.gap;
    let width = columns * cell_width + (columns + 1) * gap;
    let height = rows * cell_height + (rows + 1) * gap;

    let mut canvas = RgbImage::from_pixel(width, height, image::Rgb(BACKGROUND));
    let origin = |index: usize| {
        let (column, row) = (index as u32 % columns, index as u32 / columns);
        (
            gap + column * (cell_width + gap),
            gap + row * (cell_height + gap),
        )
    };
    for (index, picture) in pictures.iter().enumerate() {
        let (x, y) = origin(index);
        imageops::replace(&mut canvas, picture, i64::from(x), i64::from(y));
    }
    if captioned {
        let mut pixels = canvas.into_raw();
        {
            let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
            let style = (font_family(), font_size)
                .into_font()
                .color(&RGBColor(230, 230, 230));
            for (index, panel) in layout.panels.iter().enumerate() {
                let (x, y) = origin(index);
                let baseline = y + picture_height + font_size / 3;
                root.draw_text(&panel.caption, &style, (x as i32 + 4, baseline as i32))
                    .map_err(|e| format!("caption `{}`: {e}", panel.caption))?;
            }
            root.present().map_err(|e| e.to_string())?;
        }
        canvas = RgbImage::from_raw(width, height, pixels).ok_or("canvas size changed")?;
    }
    save(&canvas, &layout.output, layout.quality)
}

fn save(canvas: &RgbImage, path: &Path, quality: u8) -> Result<(), String> {
    let jpeg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("jpg") || e.eq_ignore_ascii_case("jpeg"));
    let encode_error = |e: image::ImageError| aureole_io::Error::Encode {
        path: path.to_path_buf(),
        format: if jpeg { "JPEG" } else { "PNG" },
        message: e.to_string(),
    };
    write_atomic(path, |out| {
        if jpeg {
            canvas.write_with_encoder(JpegEncoder::new_with_quality(out, quality))
        } else {
            canvas.write_to(out, ImageFormat::Png)
        }
        .map_err(encode_error)
    })
    .map_err(|e| e.to_string())
}
