//! Figure files: every figure is drawn as SVG ([`super::svg`]) and written as SVG, PNG or
//! PDF ([`FigureFormat`]). PNG is rendered by resvg (tiny-skia), PDF by svg2pdf, both from
//! the same usvg tree, with the font embedded in the binary (Plot Sans, a subset of
//! Liberation Sans, metric-compatible with the Helvetica / Arial the SVG asks for; OFL 1.1,
//! `assets/fonts/`): the output does not depend on the fonts installed, and a machine
//! without any renders the same image. PDF keeps text as text (the font subset embedded).
//!
//! The format of a figure path ([`figure_path`]): `--format` wins; without it, the path's
//! extension (`.svg`, `.png`, `.pdf`, any case) decides, and a path without an extension is
//! SVG. With `--format`, the written file always ends in the format's extension: a figure
//! extension of the path is replaced (`fig.svg` with `--format png` writes `fig.png`), any
//! other ending is kept and the extension appended.

use super::ReportError;
use resvg::{tiny_skia, usvg};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The file formats of a figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FigureFormat {
    /// The SVG document itself.
    #[default]
    Svg,
    /// A raster image, [`PNG_SCALE`] device pixels per SVG pixel.
    Png,
    /// One vector page of the SVG's size at [`PDF_PX_PER_INCH`].
    Pdf,
}

/// PNG pixels per SVG pixel: a 720 px wide plot becomes 2160 px, 300 dpi when printed at the
/// SVG's own size (7.5 in at CSS's 96 px per inch), the resolution journals ask for.
pub const PNG_SCALE: f32 = 3.0;
/// SVG pixels per inch on the PDF page: CSS's 96, so a 720 px plot is a 7.5 in wide page,
/// the size a browser prints the SVG at.
pub const PDF_PX_PER_INCH: f32 = 96.0;

/// The embedded font, regular and bold (the titles).
const FONT_REGULAR: &[u8] = include_bytes!("../../assets/fonts/PlotSans-Regular.ttf");
const FONT_BOLD: &[u8] = include_bytes!("../../assets/fonts/PlotSans-Bold.ttf");
/// Its family name, given to every generic family and as the default.
const FONT_FAMILY: &str = "Plot Sans";

impl FigureFormat {
    /// Every format, in the order the help lists them.
    pub const ALL: [FigureFormat; 3] = [FigureFormat::Svg, FigureFormat::Png, FigureFormat::Pdf];

    /// The file extension (also the name on the command line).
    pub fn ext(self) -> &'static str {
        match self {
            FigureFormat::Svg => "svg",
            FigureFormat::Png => "png",
            FigureFormat::Pdf => "pdf",
        }
    }

    /// The format named `s` (`svg`, `png`, `pdf`, any case).
    pub fn from_name(s: &str) -> Option<FigureFormat> {
        Self::ALL
            .into_iter()
            .find(|f| f.ext().eq_ignore_ascii_case(s))
    }
}

/// Errors of writing a figure.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The figure path ends in an extension that is no figure format, and no `--format`.
    #[error("{path}: unknown figure extension `.{ext}` (svg, png or pdf; or give --format)")]
    UnknownExtension {
        /// The path given.
        path: PathBuf,
        /// Its extension.
        ext: String,
    },
    /// The SVG could not be parsed (a bug of the SVG writer).
    #[error("figure not rendered: {0}")]
    Parse(String),
    /// The image is empty or too large for a pixmap.
    #[error("figure not rendered: a {width} × {height} px image cannot be drawn")]
    Size {
        /// Pixels.
        width: f32,
        /// Pixels.
        height: f32,
    },
    /// PNG encoding or PDF conversion failed.
    #[error("figure not rendered: {0}")]
    Encode(String),
}

/// The file a figure is written to and its format, from the path asked for and `--format`
/// (module docs: `--format` wins over the extension).
pub fn figure_path(
    path: &Path,
    format: Option<FigureFormat>,
) -> Result<(PathBuf, FigureFormat), FigureError> {
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned());
    let by_ext = ext.as_deref().and_then(FigureFormat::from_name);
    match (format, by_ext, ext) {
        (Some(f), Some(_), _) => Ok((path.with_extension(f.ext()), f)),
        (Some(f), None, _) => Ok((super::with_ext(path, f.ext()), f)),
        (None, Some(f), _) => Ok((path.to_path_buf(), f)),
        (None, None, None) => Ok((path.to_path_buf(), FigureFormat::Svg)),
        (None, None, Some(ext)) => Err(FigureError::UnknownExtension {
            path: path.to_path_buf(),
            ext,
        }),
    }
}

/// The bytes of the figure `svg` in `format`.
pub fn render(svg: &str, format: FigureFormat) -> Result<Vec<u8>, FigureError> {
    if format == FigureFormat::Svg {
        return Ok(svg.as_bytes().to_vec());
    }
    let tree =
        usvg::Tree::from_str(svg, &options()).map_err(|e| FigureError::Parse(e.to_string()))?;
    match format {
        FigureFormat::Svg => Ok(svg.as_bytes().to_vec()),
        FigureFormat::Png => png(&tree),
        FigureFormat::Pdf => pdf(&tree),
    }
}

/// Render `svg` in `format` and write it to `path` (parent directories created).
pub fn write_figure(path: &Path, svg: &str, format: FigureFormat) -> Result<(), ReportError> {
    let bytes = render(svg, format).map_err(|source| ReportError::Figure {
        path: path.to_path_buf(),
        source,
    })?;
    super::create_parent(path)?;
    Ok(crate::output_file::write_whole(path, &bytes)?)
}

/// Parser options: only the embedded font, standing in for every family the SVG names.
fn options() -> usvg::Options<'static> {
    let mut db = usvg::fontdb::Database::new();
    db.load_font_data(FONT_REGULAR.to_vec());
    db.load_font_data(FONT_BOLD.to_vec());
    db.set_sans_serif_family(FONT_FAMILY);
    db.set_serif_family(FONT_FAMILY);
    db.set_monospace_family(FONT_FAMILY);
    usvg::Options {
        font_family: FONT_FAMILY.into(),
        fontdb: Arc::new(db),
        ..usvg::Options::default()
    }
}

fn png(tree: &usvg::Tree) -> Result<Vec<u8>, FigureError> {
    let size = tree.size().to_int_size().scale_by(PNG_SCALE);
    let (width, height) = (tree.size().width(), tree.size().height());
    let size = size.ok_or(FigureError::Size { width, height })?;
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or(FigureError::Size { width, height })?;
    let scale = tiny_skia::Transform::from_scale(PNG_SCALE, PNG_SCALE);
    resvg::render(tree, scale, &mut pixmap.as_mut());
    pixmap
        .encode_png()
        .map_err(|e| FigureError::Encode(e.to_string()))
}

fn pdf(tree: &usvg::Tree) -> Result<Vec<u8>, FigureError> {
    let page = svg2pdf::PageOptions {
        dpi: PDF_PX_PER_INCH,
    };
    svg2pdf::to_pdf(tree, svg2pdf::ConversionOptions::default(), page)
        .map_err(|e| FigureError::Encode(e.to_string()))
}
