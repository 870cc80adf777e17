//! The compressions an EXR file can be written with: every one the `exr`
//! crate writes, by the names OpenEXR's tools use.

use std::fmt;

/// An OpenEXR compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compression {
    /// None: the largest files, the fastest to write and read.
    None,
    /// Run-length: lossless, fast, for flat areas.
    Rle,
    /// Deflate per scanline: lossless.
    Zips,
    /// Deflate per 16 scanlines: lossless, OpenEXR's usual choice.
    Zip,
    /// Wavelet and Huffman: lossless, good on grainy images.
    Piz,
    /// Float samples rounded to 24 bits, then deflate: lossy for float.
    Pxr24,
    /// 4×4 blocks of half samples: lossy, fixed rate.
    B44,
    /// B44 with flat blocks smaller.
    B44a,
    /// DCT, 32 scanlines: lossy.
    Dwaa,
    /// DCT, 256 scanlines: lossy.
    Dwab,
}

impl Compression {
    /// Every compression, in the order a list shows them.
    pub const ALL: [Compression; 10] = [
        Compression::None,
        Compression::Rle,
        Compression::Zips,
        Compression::Zip,
        Compression::Piz,
        Compression::Pxr24,
        Compression::B44,
        Compression::B44a,
        Compression::Dwaa,
        Compression::Dwab,
    ];

    /// Its name, lower case, as OpenEXR's tools write it.
    pub fn name(self) -> &'static str {
        match self {
            Compression::None => "none",
            Compression::Rle => "rle",
            Compression::Zips => "zips",
            Compression::Zip => "zip",
            Compression::Piz => "piz",
            Compression::Pxr24 => "pxr24",
            Compression::B44 => "b44",
            Compression::B44a => "b44a",
            Compression::Dwaa => "dwaa",
            Compression::Dwab => "dwab",
        }
    }

    /// Whether it keeps every sample exactly (B44 and PXR24 are exact for
    /// half samples only).
    pub fn lossless(self) -> bool {
        matches!(
            self,
            Compression::None
                | Compression::Rle
                | Compression::Zips
                | Compression::Zip
                | Compression::Piz
        )
    }

    /// The compression named `name` (any case), or a message listing them.
    pub fn parse(name: &str) -> Result<Compression, String> {
        let wanted = name.trim().to_ascii_lowercase();
        Compression::ALL
            .into_iter()
            .find(|c| c.name() == wanted)
            .ok_or_else(|| {
                let names: Vec<&str> = Compression::ALL.iter().map(|c| c.name()).collect();
                format!(
                    "{name:?} is not an EXR compression: use one of {}",
                    names.join(", ")
                )
            })
    }

    pub(crate) fn to_exr(self) -> exr::compression::Compression {
        use exr::compression::Compression as X;
        match self {
            Compression::None => X::Uncompressed,
            Compression::Rle => X::RLE,
            Compression::Zips => X::ZIP1,
            Compression::Zip => X::ZIP16,
            Compression::Piz => X::PIZ,
            Compression::Pxr24 => X::PXR24,
            Compression::B44 => X::B44,
            Compression::B44a => X::B44A,
            Compression::Dwaa => X::DWAA(None),
            Compression::Dwab => X::DWAB(None),
        }
    }

    /// The compression of an `exr` header; `None` for one we do not
    /// write (HTJ2K).
    pub(crate) fn from_exr(compression: exr::compression::Compression) -> Option<Compression> {
        use exr::compression::Compression as X;
        Compression::ALL
            .into_iter()
            .find(|c| match (c.to_exr(), compression) {
                (X::DWAA(_), X::DWAA(_)) | (X::DWAB(_), X::DWAB(_)) => true,
                (ours, theirs) => ours == theirs,
            })
    }
}

impl fmt::Display for Compression {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
