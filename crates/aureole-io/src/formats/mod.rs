//! Every file format aureole reads or writes, in one table: how a file is
//! recognised (by its content when read, by its extension when written),
//! what decodes and encodes it, and whether it holds linear light or a
//! picture for a display. A new format is one module and one entry in
//! [`FORMATS`]; every list of formats in a message comes from the table.

pub(crate) mod exr;
pub mod pfm;
pub(crate) mod picture;
pub(crate) mod radiance;
pub use radiance::{read_view as read_radiance_view, STANDARD_PRIMARIES as RADIANCE_PRIMARIES};

use std::path::Path;

use aureole::image::{Image, Primaries};

use crate::compression::Compression;
use crate::display::Depth;
use crate::error::Result;
use crate::limits::Limits;
use crate::spares::Spares;

/// What a format holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Linear light in the image's own units (HDR).
    Linear,
    /// A picture for a display: exposed, tone mapped, sRGB-encoded.
    Picture,
}

/// How a format stores a convolution kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KernelStorage {
    /// It does not.
    Unsupported,
    /// Its planes, float32, as they are.
    Planes,
    /// A log-scaled picture for people.
    LogPicture,
}

/// One file format.
pub struct Format {
    /// Its name in messages, e.g. `OpenEXR`.
    pub name: &'static str,
    /// File name extensions, lower case; the first is the usual one.
    pub extensions: &'static [&'static str],
    /// How it holds a kernel.
    pub kernels: KernelStorage,
    /// Whether it holds negative values (a glare-only result has them).
    pub signed: bool,
    /// Whether it holds named layers beside the result (glare layers).
    pub layers: bool,
    /// The sample depths a picture may have, the default first (none for
    /// linear formats).
    pub depths: &'static [Depth],
    /// Whether a file starting with these bytes is in this format.
    pub(crate) magic: fn(&[u8]) -> bool,
    /// Decodes a whole file (the layer and part chosen, where it has
    /// several); the error is one line.
    pub(crate) decode: fn(&[u8], Limits, &Choice, &Spares) -> std::result::Result<Decoded, String>,
    /// Writes it.
    pub(crate) encode: Encoder,
}

impl Format {
    /// Linear light or a picture: what its encoder writes.
    pub fn kind(&self) -> Kind {
        match self.encode {
            Encoder::Linear(_) => Kind::Linear,
            Encoder::Picture(_) => Kind::Picture,
        }
    }
}

/// How a format is written.
pub(crate) enum Encoder {
    /// Linear planes, through our own or the `exr` crate's encoder.
    Linear(fn(&Path, LinearPlanes) -> Result<Vec<Note>>),
    /// An 8 or 16-bit RGB picture through the `image` crate.
    Picture(image::ImageFormat),
}

/// What a decoder found in a file.
#[derive(Debug, Clone)]
pub(crate) struct Decoded {
    pub image: aureole::Image,
    /// An 8/16-bit display image, sRGB-decoded: its luminance is relative.
    pub display_referred: bool,
    pub notes: Vec<String>,
    /// The file's compression, where the format has a choice (EXR).
    pub compression: Option<Compression>,
    /// The rest of the file, for writing the result back into it.
    pub original: Original,
}

/// What a file held besides the planes aureole spreads (for an EXR: its
/// other layers and parts, windows, attributes, channel names and types),
/// so that a result written in the same format keeps it.
#[derive(Debug, Clone, Default)]
pub struct Original {
    pub(crate) exr: Option<Box<exr::Kept>>,
    pub(crate) radiance: Option<radiance::Header>,
    /// Layers of glare to write beside the result (EXR only).
    pub(crate) glare: Vec<aureole::GlareLayer>,
    /// Where the writer takes its buffers from and gives them back: those
    /// the file was read with.
    pub(crate) spares: Spares,
}

impl Original {
    /// Whether the file was a Radiance picture.
    pub fn is_radiance(&self) -> bool {
        self.radiance.is_some()
    }

    /// A Radiance picture's view options (its `VIEW=` lines), as
    /// [`aureole::View::from_radiance`] reads them.
    pub fn radiance_view(&self) -> Option<&str> {
        self.radiance.as_ref().and_then(|h| h.view.as_deref())
    }

    /// The parts, layers and channels of the file, a line each, for a
    /// person; empty for a format without them.
    pub fn describe(&self) -> Vec<String> {
        self.exr.as_ref().map(|k| k.describe()).unwrap_or_default()
    }

    /// Where an EXR's display window lies in the frame's pixels (its
    /// data window); `None` for a format without one.
    pub fn display_window(&self) -> Option<aureole::DisplayWindow> {
        self.exr.as_ref().and_then(|k| k.display_window())
    }

    /// The images of a multi-view file's other views (an EXR's second eye),
    /// each with its glare layers: each front end puts every one through
    /// the camera, and an EXR result holds whatever they hold when written,
    /// the layers beside their view's result, in its own part or named for
    /// the view in a single-part multi-view file.
    pub fn views_mut(
        &mut self,
    ) -> impl Iterator<Item = (&mut Image, &mut Vec<aureole::GlareLayer>)> {
        self.exr.iter_mut().flat_map(|k| k.views_mut())
    }

    /// Writes `layers` beside the result, each under its name next to the
    /// spread layer (`glare.bloom.R` beside `R`, `ViewLayer.glare.R`
    /// beside `ViewLayer.Combined.R`), replacing channels of the same
    /// names. Only a format whose `layers` is set holds them
    /// ([`crate::job::Request::check`] refuses the others).
    pub fn add_glare_layers(&mut self, layers: Vec<aureole::GlareLayer>) {
        self.glare = layers;
    }

    /// What a kernel file records of what it was built for
    /// ([`crate::kernel::write_kernel_for`]).
    pub fn recorded_kernel(&self) -> KernelRecord {
        self.exr
            .as_ref()
            .map_or_else(KernelRecord::default, |k| k.recorded_kernel())
    }
}

/// How samples are stored, where the format has a choice (EXR).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Samples {
    /// 16-bit half floats.
    Half,
    /// 32-bit floats.
    Float,
}

/// Linear planes to write, borrowed from an image or a kernel.
pub(crate) struct LinearPlanes<'a> {
    pub width: usize,
    pub height: usize,
    /// One plane (`Y`) or three (`R`, `G`, `B`).
    pub colour: Vec<&'a [f32]>,
    pub alpha: Option<&'a [f32]>,
    pub white_luminance: Option<f32>,
    pub primaries: Option<Primaries>,
    /// Half or float, where the format has the choice; `None`: as read,
    /// else float.
    pub samples: Option<Samples>,
    /// The compression, where the format has a choice (EXR); `None`: as
    /// read, else ZIP.
    pub compression: Option<Compression>,
    /// The file the image was read from, to write the result back into.
    pub original: Original,
    /// For a kernel: what it was built for, recorded where the format can
    /// (EXR).
    pub kernel: KernelRecord,
}

/// What a kernel file records of the camera it was built from, so that
/// applying it gives what applying that camera gives.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KernelRecord {
    /// The width of the images it was built for: its µm and mm became
    /// pixels at that pitch.
    pub image_width: Option<usize>,
    /// The camera's threshold, cd/m², which `apply --kernel` uses unless
    /// told another.
    pub threshold: Option<f64>,
    /// The least share of its PSF's light any plane holds, where the file
    /// says its planes hold shares ([`LIGHT_ATTRIBUTE`]): read as they
    /// are, not normalised to 1.
    pub shares: Option<f64>,
}

/// What a writer could not keep, for the user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Note {
    /// Samples beyond the largest half float, written as ±65504.
    ClampedToHalf {
        /// How many.
        count: usize,
    },
    /// Samples near or beyond the largest half float in channels that a
    /// lossy compression stores as half (DWAA and DWAB: R, G, B, Y, RY,
    /// BY), lowered so that they do not come back infinite.
    ClampedForCompression {
        /// How many.
        count: usize,
        /// The compression.
        compression: Compression,
        /// The largest magnitude they were written with, rounded down.
        ceiling: u32,
    },
    /// Negative samples that the format cannot hold, written as 0.
    NegativesZeroed {
        /// How many.
        count: usize,
        /// The format, in words.
        format: &'static str,
    },
    /// The format has no alpha channel.
    AlphaDropped {
        /// The format, in words.
        format: &'static str,
    },
}

impl std::fmt::Display for Note {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Note::ClampedToHalf { count } => write!(
                f,
                "{count} samples beyond ±{HALF_MAX} (the largest half float) written as ±{HALF_MAX}"
            ),
            Note::ClampedForCompression {
                count,
                compression,
                ceiling,
            } => write!(
                f,
                "{count} samples near or beyond ±{HALF_MAX} written as at most ±{ceiling}: {compression} stores R, G, B and Y as lossy half floats, which would come back infinite; zip, piz or none keep them"
            ),
            Note::NegativesZeroed { count, format } => write!(
                f,
                "{format} holds no negative values: {count} samples written as 0"
            ),
            Note::AlphaDropped { format } => {
                write!(f, "{format} has no alpha channel: alpha not written")
            }
        }
    }
}

/// The largest finite half float.
pub const HALF_MAX: f32 = 65504.0;

/// Every format, in the order messages list them.
pub static FORMATS: &[Format] = &[
    Format {
        name: "OpenEXR",
        signed: true,
        layers: true,
        extensions: &["exr"],
        kernels: KernelStorage::Planes,
        depths: &[],
        magic: |head| head.starts_with(&[0x76, 0x2f, 0x31, 0x01]),
        decode: exr::decode,
        encode: Encoder::Linear(exr::encode),
    },
    Format {
        name: "Radiance HDR",
        signed: false,
        layers: false,
        extensions: &["hdr"],
        kernels: KernelStorage::Unsupported,
        depths: &[],
        magic: |head| head.starts_with(b"#?"),
        decode: |bytes, limits, _, _| radiance::decode(bytes, limits),
        encode: Encoder::Linear(radiance::encode),
    },
    Format {
        name: "PFM",
        signed: true,
        layers: false,
        extensions: &["pfm"],
        kernels: KernelStorage::Planes,
        depths: &[],
        magic: |head| head.starts_with(b"PF") || head.starts_with(b"Pf"),
        decode: |bytes, limits, _, _| pfm::decode_file(bytes, limits),
        encode: Encoder::Linear(pfm::encode),
    },
    Format {
        name: "PNG",
        signed: false,
        layers: false,
        extensions: &["png"],
        kernels: KernelStorage::LogPicture,
        depths: &[Depth::Eight, Depth::Sixteen],
        magic: |head| head.starts_with(b"\x89PNG"),
        decode: |bytes, limits, _, _| picture::decode(bytes, limits),
        encode: Encoder::Picture(image::ImageFormat::Png),
    },
    Format {
        name: "JPEG",
        signed: false,
        layers: false,
        extensions: &["jpg", "jpeg"],
        kernels: KernelStorage::Unsupported,
        depths: &[Depth::Eight],
        magic: |head| head.starts_with(&[0xff, 0xd8, 0xff]),
        decode: |bytes, limits, _, _| picture::decode(bytes, limits),
        encode: Encoder::Picture(image::ImageFormat::Jpeg),
    },
    Format {
        name: "TIFF",
        signed: false,
        layers: false,
        extensions: &["tif", "tiff"],
        kernels: KernelStorage::Unsupported,
        depths: &[Depth::Sixteen, Depth::Eight],
        magic: |head| head.starts_with(b"II*\0") || head.starts_with(b"MM\0*"),
        decode: |bytes, limits, _, _| picture::decode(bytes, limits),
        encode: Encoder::Picture(image::ImageFormat::Tiff),
    },
];

/// The lower-case extension of `path`, empty if none.
pub fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

/// The format a file called `path` is written in, by its extension.
pub fn by_extension(path: &Path) -> Option<&'static Format> {
    let extension = extension(path);
    FORMATS
        .iter()
        .find(|f| f.extensions.contains(&extension.as_str()))
}

/// The format of a file that starts with `head`.
pub fn by_content(head: &[u8]) -> Option<&'static Format> {
    FORMATS.iter().find(|f| (f.magic)(head))
}

/// The formats we read, for messages: `OpenEXR, …, JPEG or TIFF`.
pub fn readable() -> String {
    let names: Vec<&str> = FORMATS.iter().map(|f| f.name).collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.join(""),
    }
}

/// The extensions an image may be written to, for messages:
/// `.exr, .hdr, .pfm (linear) or .png, .jpg, .tif (for display)`.
pub fn image_outputs() -> String {
    let of = |kind: Kind| {
        FORMATS
            .iter()
            .filter(|f| f.kind() == kind)
            .map(|f| format!(".{}", f.extensions[0]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "{} (linear) or {} (for display)",
        of(Kind::Linear),
        of(Kind::Picture)
    )
}

/// The extensions a linear image may be written to, for messages:
/// `.exr, .hdr, .pfm`.
pub fn linear_outputs() -> String {
    FORMATS
        .iter()
        .filter(|f| f.kind() == Kind::Linear)
        .map(|f| format!(".{}", f.extensions[0]))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The extensions a picture may be written to, with their depths.
pub fn picture_outputs() -> String {
    FORMATS
        .iter()
        .filter(|f| f.kind() == Kind::Picture)
        .map(|f| {
            let bits: Vec<String> = sorted_depths(f)
                .iter()
                .map(|d| d.bits().to_string())
                .collect();
            format!(".{} ({}-bit)", f.extensions[0], bits.join(" or "))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The extensions a kernel may be written to, with what they hold.
pub fn kernel_outputs() -> String {
    FORMATS
        .iter()
        .filter_map(|f| {
            let what = match f.kernels {
                KernelStorage::Unsupported => return None,
                KernelStorage::Planes => "float32",
                KernelStorage::LogPicture => "log-scaled picture",
            };
            Some(format!(".{} ({what})", f.extensions[0]))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The linear formats that hold negative values, for a message:
/// `.exr or .pfm`.
pub fn signed_outputs() -> String {
    FORMATS
        .iter()
        .filter(|f| f.signed && f.kind() == Kind::Linear)
        .map(|f| format!(".{}", f.extensions[0]))
        .collect::<Vec<_>>()
        .join(" or ")
}

/// The formats that hold glare layers, for a message: their names and
/// their extensions (`OpenEXR`, `.exr`).
pub fn layered_outputs() -> (String, String) {
    let layered = || FORMATS.iter().filter(|f| f.layers);
    let names: Vec<&str> = layered().map(|f| f.name).collect();
    let extensions: Vec<String> = layered().map(|f| format!(".{}", f.extensions[0])).collect();
    (names.join(" or "), extensions.join(" or "))
}

/// The pictures that hold `depth`, for a message: `.png or .tif`.
pub(crate) fn holding(depth: Depth) -> String {
    FORMATS
        .iter()
        .filter(|f| f.depths.contains(&depth))
        .map(|f| format!(".{}", f.extensions[0]))
        .collect::<Vec<_>>()
        .join(" or ")
}

fn sorted_depths(format: &Format) -> Vec<Depth> {
    let mut depths = format.depths.to_vec();
    depths.sort_by_key(|d| d.bits());
    depths
}

/// The EXR attribute that records the width of the images a kernel was
/// built for: its µm and mm became pixels at that pitch.
pub const IMAGE_WIDTH_ATTRIBUTE: &str = "aureoleImageWidth";

/// The EXR attribute that records the threshold (cd/m²) of the camera a
/// kernel was built from.
pub const THRESHOLD_ATTRIBUTE: &str = "aureoleThreshold";

/// The EXR attribute that says a kernel's planes hold the shares of their
/// PSFs' light that fall within them (the least of them, for a reader):
/// the light beyond leaves the frame, so a reader keeps the sums as they
/// are rather than normalising them to 1.
pub const LIGHT_ATTRIBUTE: &str = "aureoleLightKept";

/// Which of a file's layers and parts to read (OpenEXR); by default the
/// beauty, as compositors find it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Choice {
    /// The layer, by its channel-name prefix (`ViewLayer.Combined` for
    /// `ViewLayer.Combined.R`, …).
    pub layer: Option<String>,
    /// The part, by its index (from 0) or name.
    pub part: Option<String>,
}

impl Choice {
    /// Whether anything is chosen.
    pub fn is_some(&self) -> bool {
        self.layer.is_some() || self.part.is_some()
    }
}

pub use aureole::image::Shape;

/// A decoder's message in the user's words: most of the ways a file can be
/// cut short surface as one of these.
pub(crate) fn explain(format: &str, message: String) -> String {
    // Some decoders' messages span lines; ours are one line each.
    let message = message.split_whitespace().collect::<Vec<_>>().join(" ");
    let lower = message.to_lowercase();
    let truncated = [
        "missing bytes",
        "fill whole buffer",
        "unexpected end",
        "unexpected eof",
        "eof in header",
    ]
    .iter()
    .any(|m| lower.contains(m));
    if truncated {
        format!("cannot read {format}: the file ends early (truncated?): {message}")
    } else {
        format!("cannot read {format}: {message}")
    }
}
