//! `aureole presets [NAME]`.

use std::io::Write;

use aureole::presets::{find, PRESETS};

use crate::Failure;

#[derive(clap::Args)]
pub struct Args {
    /// Print this preset's TOML (a config file to start from) instead of the list.
    name: Option<String>,
}

pub fn run(args: &Args) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    let text = match &args.name {
        Some(name) => find(name)?.toml.to_string(),
        None => {
            let width = PRESETS.iter().map(|p| p.name.len()).max().unwrap_or(0);
            PRESETS
                .iter()
                .map(|p| format!("{:width$}  {}\n", p.name, p.description()))
                .collect()
        }
    };
    // A closed pipe (`aureole presets | head`) is not an error worth a message.
    let _ = out.write_all(text.as_bytes());
    Ok(())
}
