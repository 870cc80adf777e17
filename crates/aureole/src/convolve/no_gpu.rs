//! The GPU engine's place in a build without it (the cargo feature `gpu`
//! off): no adapter is ever found, so [`super::choose`] keeps every
//! convolution on the CPU and [`crate::Device::Gpu`] says why.

use std::sync::Arc;

use super::{Footprint, Load};

/// Why there is no GPU to compute on.
const ABSENT: &str = "this build of aureole has no GPU engine (the cargo feature `gpu` is off)";

/// A GPU adapter: none can exist in this build.
#[derive(Debug)]
pub enum Gpu {}

impl Gpu {
    /// The adapter's name.
    pub fn name(&self) -> String {
        match *self {}
    }

    /// Whether it is a software rasteriser.
    pub fn is_software(&self) -> bool {
        match *self {}
    }
}

/// Never an adapter: why there is none.
pub fn gpu() -> Result<Arc<Gpu>, String> {
    Err(ABSENT.into())
}

/// No software adapter either.
pub fn software_adapter() -> Option<String> {
    None
}

/// Nothing to look for.
pub fn look_ahead() {}

/// Nothing was looked for.
pub fn looked() {}

/// Never asked: no engine is built on a GPU in this build.
pub(super) fn footprint(_load: &Load) -> Footprint {
    Footprint {
        preparing: 0,
        spreading: 0,
    }
}

#[cfg(test)]
mod tests {
    use crate::convolve::{choose, Backend};
    use crate::{Device, Error};

    #[test]
    fn without_the_engine_auto_computes_on_the_cpu_and_gpu_says_why() {
        let (backend, words) = choose(Device::Auto).unwrap();
        assert_eq!(backend, Backend::Cpu);
        assert!(words.starts_with("the CPU: this build of aureole has no GPU engine"));
        let Err(Error::NoGpu(why)) = choose(Device::Gpu) else {
            panic!("Device::Gpu without the engine");
        };
        assert!(why.contains("the cargo feature `gpu` is off"), "{why}");
    }
}
