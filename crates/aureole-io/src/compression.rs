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

    /// Whether it keeps every sample exactly (PXR24 keeps half samples
    /// exactly, float ones to 24 bits).
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

    /// Whether it keeps half samples exactly.
    pub fn exact_for_half(self) -> bool {
        self.lossless() || self == Compression::Pxr24
    }

    /// Every name, grouped by what each keeps: `none, …, piz; exact for
    /// half samples only: pxr24; lossy: b44, …`.
    pub fn names() -> String {
        let of = |chosen: &dyn Fn(Compression) -> bool| {
            let names: Vec<&str> = Compression::ALL
                .into_iter()
                .filter(|c| chosen(*c))
                .map(Compression::name)
                .collect();
            names.join(", ")
        };
        format!(
            "{}; exact for half samples only: {}; lossy: {}",
            of(&|c| c.lossless()),
            of(&|c| !c.lossless() && c.exact_for_half()),
            of(&|c| !c.lossless() && !c.exact_for_half()),
        )
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

impl std::str::FromStr for Compression {
    type Err = String;

    /// The compression named `name` (any case), or a message listing them.
    fn from_str(name: &str) -> Result<Compression, String> {
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
}

impl fmt::Display for Compression {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
