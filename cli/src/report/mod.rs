//! Rendering of the studies' results: CSV tables ([`csv`]), SVG figures ([`svg`] and the
//! figures of each study), the accuracy Markdown ([`accuracy_doc`]), and writing files.
//! Nothing here calls the estimator: every function takes computed results.
//!
//! | module | what |
//! |---|---|
//! | [`svg`] | the SVG writer: line plots, heat maps |
//! | [`calibration`](mod@calibration) | `cablevib calibrate`: measured against model frequency |
//! | [`calibrated_scene`] | `cablevib calibrate -o`: the calibrated scene file |
//! | [`figure`] | figure files: SVG, or PNG / PDF rendered from it (`--format`) |
//! | [`csv`] | the one CSV writer (`csv` crate, `PATH.json` sidecars) and the number formats of every command's CSV |
//! | [`map`](mod@map) | `cablevib map`: CSV and heat-map figure |
//! | [`trajectory`](mod@trajectory) | `cablevib trajectory`: CSV and figure |
//! | [`shapes_csv`] | `cablevib modes`: the mode-shape CSV |
//! | [`tmin`] | `cablevib sweep-tmin`: CSV and figure |
//! | [`hold`](mod@hold) | `cablevib demo --hold-f1 --hold-csv`: the figures of the hold's record |
//! | [`sag_compare`] | `cablevib sag-compare`: CSV and four-panel figure |
//! | [`accuracy_figures`] | `cablevib accuracy`: CSVs and figures |
//! | [`accuracy_doc`] | `cablevib accuracy`: the Markdown section and its splicing |

pub mod accuracy_doc;
pub mod accuracy_figures;
pub mod calibrated_scene;
pub mod calibration;
pub mod csv;
pub mod figure;
pub mod frf;
pub mod hold;
pub mod identify;
pub mod map;
pub mod sag_compare;
pub mod shapes_csv;
pub mod svg;
pub mod tmin;
pub mod trajectory;

use std::path::{Path, PathBuf};

/// Errors of writing reports.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// An output file was refused or could not be written whole.
    #[error(transparent)]
    Output(#[from] crate::output_file::OutputFileError),
    /// A figure could not be rendered to its format.
    #[error("{path}: {source}")]
    Figure {
        /// File.
        path: PathBuf,
        /// Why.
        source: figure::FigureError,
    },
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Write `text` to `path` whole or not at all ([`crate::output_file`]), creating parent
/// directories.
pub fn write_file(path: &Path, text: &str) -> Result<(), ReportError> {
    create_parent(path)?;
    Ok(crate::output_file::write_whole(path, text.as_bytes())?)
}

/// Create the parent directories of `path`.
fn create_parent(path: &Path) -> Result<(), ReportError> {
    if let Some(d) = path.parent() {
        if !d.as_os_str().is_empty() {
            std::fs::create_dir_all(d).map_err(io_err(d))?;
        }
    }
    Ok(())
}

/// `PREFIX` + `ext` (`map` → `map.csv`), keeping any dots already in the prefix.
pub fn with_ext(prefix: &Path, ext: &str) -> PathBuf {
    let mut s = prefix.as_os_str().to_os_string();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// Relative difference below which the end-effector mode counts as f1 itself (then its
/// curve is not drawn again).
const SAME_MODE_REL: f64 = 1e-9;

/// Whether the end-effector-mode curve `ee` differs anywhere from the f1 curve `f1`
/// (same x values).
pub(crate) fn ee_curve_differs(f1: &[(f64, f64)], ee: &[(f64, f64)]) -> bool {
    f1.iter()
        .zip(ee)
        .any(|(a, b)| b.1.is_finite() && (a.1 - b.1).abs() > SAME_MODE_REL * b.1.abs())
}
