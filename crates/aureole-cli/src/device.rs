//! `--device`, as `apply`, `psf` and `studio` take it.

/// `--device`: where the convolutions run.
#[derive(Clone, Copy, clap::ValueEnum)]
pub(crate) enum DeviceArg {
    Auto,
    Cpu,
    Gpu,
}

impl From<DeviceArg> for aureole::Device {
    fn from(device: DeviceArg) -> aureole::Device {
        match device {
            DeviceArg::Auto => aureole::Device::Auto,
            DeviceArg::Cpu => aureole::Device::Cpu,
            DeviceArg::Gpu => aureole::Device::Gpu,
        }
    }
}
