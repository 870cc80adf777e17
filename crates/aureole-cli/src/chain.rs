//! The options that say which camera to simulate, shared by the commands:
//! presets and config files composed in command-line order, and the seed.

use std::path::PathBuf;

use aureole::{presets, Config, ConfigFile};
use clap::ArgMatches;

use crate::Failure;

#[derive(clap::Args)]
pub struct ChainArgs {
    /// A built-in preset (see `aureole presets`); repeatable.
    #[arg(long, value_name = "NAME")]
    pub preset: Vec<String>,

    /// A TOML config file (seed, threshold, [camera], [[effect]] …); repeatable.
    #[arg(long, value_name = "FILE")]
    pub config: Vec<PathBuf>,

    /// Seed of the random ray lengths (and widths, intensities) of a corona;
    /// overrides the config's `seed`.
    #[arg(long, value_name = "N")]
    pub seed: Option<u64>,
}

impl ChainArgs {
    /// Whether the user named any preset or config.
    pub fn is_empty(&self) -> bool {
        self.preset.is_empty() && self.config.is_empty()
    }

    /// The configuration the sources make, in the order they stand in
    /// `matches` (the subcommand's): later settings replace earlier ones,
    /// effects are appended.
    /// A measured PSF's picture that cannot hold it whole is warned about
    /// unless `quiet`.
    pub fn compose(&self, matches: &ArgMatches, quiet: bool) -> Result<Config, Failure> {
        let indices = |id| -> Vec<usize> {
            matches
                .indices_of(id)
                .map(|i| i.collect())
                .unwrap_or_default()
        };
        let mut sources: Vec<(usize, ConfigFile)> = Vec::new();
        for (name, index) in self.preset.iter().zip(indices("preset")) {
            sources.push((index, presets::find(name)?.config()?));
        }
        for (path, index) in self.config.iter().zip(indices("config")) {
            // Any failure to read the config is the user's to fix: exit 2.
            let mut file = ConfigFile::load(path)
                .map_err(|e| Failure::Usage(anyhow::anyhow!(crate::words::library(&e))))?;
            aureole_io::measured::resolve(&mut file, aureole_io::atomic::folder_of(path));
            sources.push((index, file));
        }
        sources.sort_by_key(|(index, _)| *index);
        let mut config = Config::default();
        for (_, file) in sources {
            config.merge(file);
        }
        if let Some(seed) = self.seed {
            config.seed = seed;
        }
        let limits = aureole_io::limits::Limits::default_for_machine();
        for warning in aureole_io::measured::load(&mut config.effects, limits)? {
            if !quiet {
                say!("aureole: warning: {warning}");
            }
        }
        Ok(config)
    }

    /// As [`compose`](Self::compose), with the default camera when no source
    /// was named.
    pub fn compose_or_default(
        &self,
        matches: &ArgMatches,
        quiet: bool,
    ) -> Result<(Config, bool), Failure> {
        let mut config = self.compose(matches, quiet)?;
        let defaulted = self.is_empty();
        if defaulted {
            config.merge(presets::find(presets::DEFAULT_PRESET)?.config()?);
        }
        if config.effects.is_empty() && config.ghosts.is_none() {
            return Err(aureole::Error::NoEffect.into());
        }
        Ok((config, defaulted))
    }
}
