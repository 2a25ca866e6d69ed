//! `cablevib completions SHELL` and `cablevib man`: shell completion scripts and the roff
//! man page, generated from the same argument definitions the parser uses (so they cannot
//! drift from it).

use super::{Cli, CliError};
use crate::output_file::stdout_bytes;
use clap::{Args, CommandFactory};
use clap_complete::Shell;

/// `cablevib completions` options.
#[derive(Debug, Clone, Args)]
pub struct CompletionsArgs {
    /// The shell: bash, zsh, fish, elvish or powershell. Install e.g. with
    /// `cablevib completions bash > ~/.local/share/bash-completion/completions/cablevib`.
    #[arg(value_enum)]
    pub shell: Shell,
}

/// `cablevib man` options.
#[derive(Debug, Clone, Args)]
pub struct ManArgs {}

/// Print the completion script for `a.shell` to stdout.
pub fn completions(a: &CompletionsArgs) -> Result<(), CliError> {
    let mut cmd = Cli::command();
    // Generated in memory (clap_complete panics when its writer fails), then written.
    let mut script = Vec::new();
    clap_complete::generate(a.shell, &mut cmd, "cablevib", &mut script);
    stdout_bytes(&script)?;
    Ok(())
}

/// Print the man page (roff, section 1) to stdout: `cablevib man > cablevib.1`.
pub fn man(_: &ManArgs) -> Result<(), CliError> {
    let page = clap_mangen::Man::new(Cli::command());
    let mut roff = Vec::new();
    page.render(&mut roff)?;
    stdout_bytes(&roff)?;
    Ok(())
}
