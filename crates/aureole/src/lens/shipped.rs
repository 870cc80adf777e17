//! The lenses that come with aureole, written from patents
//! (`crates/aureole/lenses/`): a config names one by its name, so that a
//! front end with no files of its own (the studio, Python, Blender) can
//! trace ghosts through it.

use super::Lens;

/// A lens compiled into the library.
#[derive(Debug, Clone, Copy)]
pub struct Shipped {
    /// Its name, as a config's `lens` gives it.
    pub name: &'static str,
    /// Its lens file's text.
    pub toml: &'static str,
}

macro_rules! shipped {
    ($($name:literal),* $(,)?) => {
        &[$(Shipped { name: $name, toml: include_str!(concat!("../../lenses/", $name, ".toml")) }),*]
    };
}

/// Every shipped lens, the round ones by focal length, then the
/// anamorphic.
pub const LENSES: &[Shipped] = shipped!(
    "retrofocus-28mm-f2.8",
    "double-gauss-50mm-f1.4",
    "zoom-70-200mm-f2.8-at-72mm",
    "portrait-90mm-f2",
    "telephoto-300mm-f2.8",
    "anamorphic-rear-1.3x-f1.8",
);

impl Shipped {
    /// The lens, parsed.
    pub fn lens(&self) -> crate::Result<Lens> {
        Lens::parse(self.toml, self.name)
    }
}

/// The shipped lens of that name.
pub fn find(name: &str) -> Option<&'static Shipped> {
    LENSES.iter().find(|l| l.name == name)
}

/// The names of the shipped lenses, in a list for a message.
pub fn names() -> String {
    LENSES.iter().map(|l| l.name).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_shipped_lens_parses() {
        for shipped in super::LENSES {
            let lens = shipped.lens().unwrap();
            assert!(
                lens.paraxial().unwrap().focal_length > 0.0,
                "{}",
                shipped.name
            );
        }
    }
}
