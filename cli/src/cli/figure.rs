//! `--format svg|png|pdf`, the option of every command that writes a figure, and where the
//! figure goes ([`crate::report::figure::figure_path`]: `--format` wins over the extension
//! of the figure path; without either, SVG).

use super::CliError;
use crate::report::figure::{figure_path, write_figure, FigureFormat};
use std::path::{Path, PathBuf};

/// Parse `--format` (one-line error).
pub fn parse_format(s: &str) -> Result<FigureFormat, String> {
    FigureFormat::from_name(s).ok_or_else(|| format!("expected svg, png or pdf, got `{s}`"))
}

/// The file and format of a figure asked for at `path`.
pub fn target(
    path: &Path,
    format: Option<FigureFormat>,
) -> Result<(PathBuf, FigureFormat), CliError> {
    figure_path(path, format).map_err(|e| CliError::Usage(e.to_string()))
}

/// Refuse `--format` without `--svg` in a command whose figure is written only when asked for
/// (`svg` the figure path given, if any).
pub fn format_needs_svg(
    svg: &Option<PathBuf>,
    format: Option<FigureFormat>,
) -> Result<(), CliError> {
    if format.is_some() && svg.is_none() {
        let msg = "--format needs --svg PATH (the figure is written only there)";
        return Err(CliError::Usage(msg.into()));
    }
    Ok(())
}

/// Write the figure `svg` to `path` in `format`.
pub fn write(path: &Path, svg: &str, format: FigureFormat) -> Result<(), CliError> {
    Ok(write_figure(path, svg, format)?)
}
