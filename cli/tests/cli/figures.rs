//! The figures a researcher puts in a paper: every SVG parses as XML; the legend of a line
//! plot covers no plotted line (checked on the SVG's own geometry); log axes label every
//! decade in range; `--format png|pdf` writes a decodable PNG / a one-page PDF; `--format`
//! mistakes are one-line errors.

use cablevib_cli::report::figure::{figure_path, render, FigureFormat, PNG_SCALE};
use cablevib_cli::report::svg::{Axis, HLine, LinePlot, Mark, Series};
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

/// The accuracy figure's shape on the planar robot: a straight falling line, a flat line
/// and a reference line on top of it (the case whose legend used to cover a curve).
fn crowded_plot() -> LinePlot {
    let ns: Vec<f64> = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 80.0].to_vec();
    let mut p = LinePlot::new(
        "f1 error",
        Axis::log("N"),
        Axis::log("|f1 − f1,ref| / f1,ref"),
    );
    let falling = ns.iter().map(|&n| (n, 5e-2 / (n * n))).collect();
    let flat = ns.iter().map(|&n| (n, 4e-5)).collect();
    let steep = ns.iter().map(|&n| (n, 1e-6 / (n * n * n))).collect();
    p.series.push(Series::new(
        "catenary vs reference",
        falling,
        Mark::LinePoints,
    ));
    p.series
        .push(Series::new("FEM vs reference", flat, Mark::LinePoints));
    p.series.push(Series::new(
        "FEM vs its continuous limit",
        steep,
        Mark::Dashed,
    ));
    for (name, y) in [
        ("continuous", 4e-5),
        ("massless + T/l", 1.6e-3),
        ("massless", 1.6e-3),
    ] {
        p.hlines.push(HLine {
            name: name.into(),
            y,
            color: "#CC79A7".into(),
        });
    }
    p
}

/// A plot whose legend fits in a free corner.
fn sparse_plot() -> LinePlot {
    let mut p = LinePlot::new(
        "f1 against T_min",
        Axis::linear("T_min (N)"),
        Axis::linear("f (Hz)"),
    );
    let pts = (1..=15)
        .map(|k| (5.0 * k as f64, 0.1 * (5.0 * k as f64).sqrt()))
        .collect();
    p.series.push(Series::new("f1", pts, Mark::LinePoints));
    p
}

/// A rectangle (x0, y0, x1, y1), px.
type Rect = (f64, f64, f64, f64);

fn attr(n: roxmltree::Node, a: &str) -> f64 {
    n.attribute(a)
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN)
}

/// The legend box (x0, y0, x1, y1) and every drawn point of the data, sampled every
/// 0.25 px along lines and kept only inside the clip rectangle (what is visible).
fn legend_and_samples(svg: &str) -> (Rect, Vec<(f64, f64)>) {
    let doc = roxmltree::Document::parse(svg).expect("well-formed SVG");
    let rect = |n: roxmltree::Node| {
        let (x, y) = (attr(n, "x"), attr(n, "y"));
        (x, y, x + attr(n, "width"), y + attr(n, "height"))
    };
    let legend = doc
        .descendants()
        .find(|n| n.attribute("class") == Some("legend"))
        .map(rect)
        .expect("a legend");
    let clip = doc
        .descendants()
        .find(|n| n.has_tag_name("clipPath"))
        .and_then(|c| c.children().find(|n| n.has_tag_name("rect")))
        .map(rect)
        .expect("a clip rectangle");
    let data = doc
        .descendants()
        .find(|n| n.attribute("class") == Some("data"))
        .expect("the data group");
    let mut lines: Vec<Vec<(f64, f64)>> = Vec::new();
    for n in data.descendants().filter(|n| n.is_element()) {
        match n.tag_name().name() {
            "polyline" => lines.push(
                n.attribute("points")
                    .unwrap_or("")
                    .split_whitespace()
                    .filter_map(|p| p.split_once(','))
                    .map(|(x, y)| (x.parse().unwrap_or(f64::NAN), y.parse().unwrap_or(f64::NAN)))
                    .collect(),
            ),
            "line" => lines.push(vec![
                (attr(n, "x1"), attr(n, "y1")),
                (attr(n, "x2"), attr(n, "y2")),
            ]),
            "circle" => lines.push(vec![(attr(n, "cx"), attr(n, "cy"))]),
            _ => {}
        }
    }
    let mut samples = Vec::new();
    for l in &lines {
        samples.extend(l.iter().copied());
        for w in l.windows(2) {
            let len = ((w[1].0 - w[0].0).hypot(w[1].1 - w[0].1) * 4.0).ceil() as usize;
            for k in 0..=len {
                let t = k as f64 / len.max(1) as f64;
                samples.push((
                    w[0].0 + t * (w[1].0 - w[0].0),
                    w[0].1 + t * (w[1].1 - w[0].1),
                ));
            }
        }
    }
    let inside = |p: &(f64, f64), r: (f64, f64, f64, f64)| {
        p.0 >= r.0 && p.0 <= r.2 && p.1 >= r.1 && p.1 <= r.3
    };
    samples.retain(|p| inside(p, clip));
    let hit: Vec<_> = samples.iter().filter(|p| inside(p, legend)).collect();
    assert!(
        hit.is_empty(),
        "legend {legend:?} covers drawn points {:?}",
        &hit[..hit.len().min(5)]
    );
    assert!(
        samples.len() > 100,
        "the test saw the data: {} samples",
        samples.len()
    );
    (legend, samples)
}

#[test]
fn legend_covers_no_plotted_line() {
    let (inside, _) = legend_and_samples(&sparse_plot().to_svg());
    // The sparse plot has a free corner: the legend stays inside its 720 px document.
    assert!(inside.2 < 720.0, "{inside:?}");
    let (outside, _) = legend_and_samples(&crowded_plot().to_svg());
    assert!(outside.0 > 0.0);
}

#[test]
fn log_axes_label_every_decade_in_one_style() {
    let svg = crowded_plot().to_svg();
    let doc = roxmltree::Document::parse(&svg).expect("well-formed SVG");
    let labels: Vec<String> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("tick"))
        .map(|n| {
            n.descendants()
                .filter(|t| t.is_text())
                .filter_map(|t| t.text())
                .collect::<String>()
        })
        .collect();
    // y spans 10^-10 .. 10^-1 (the steep series' 1e-6/80³ ≈ 2e-12 → 10^-12); x 1 .. 100.
    for e in -12..=-1 {
        let want = format!("10{}", e.to_string().replace('-', "−"));
        assert!(labels.contains(&want), "no label {want} in {labels:?}");
    }
    for x in ["1", "10", "100"] {
        assert!(labels.iter().any(|l| l == x), "no label {x} in {labels:?}");
    }
    // One style per axis: the y axis has no plain decimal next to its powers of ten.
    assert!(!labels.iter().any(|l| l.starts_with("0.")), "{labels:?}");
}

#[test]
fn subscripts_are_tspans() {
    let svg = sparse_plot().to_svg();
    assert!(
        svg.contains(r#" against T</tspan><tspan dy="4.0" font-size="12.0">min</tspan>"#),
        "{svg}"
    );
}

#[test]
fn png_and_pdf_render() {
    let svg = crowded_plot().to_svg();
    let png = render(&svg, FigureFormat::Png).expect("png");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR: width and height, big-endian, right after the chunk header.
    let be = |i: usize| u32::from_be_bytes([png[i], png[i + 1], png[i + 2], png[i + 3]]);
    assert_eq!(&png[12..16], b"IHDR");
    let doc = roxmltree::Document::parse(&svg).expect("xml");
    let w: f64 = doc
        .root_element()
        .attribute("width")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0);
    assert_eq!(be(16), (w * PNG_SCALE as f64).round() as u32);
    assert_eq!(be(20), (440.0 * PNG_SCALE as f64).round() as u32);
    let pdf = render(&svg, FigureFormat::Pdf).expect("pdf");
    assert!(pdf.starts_with(b"%PDF-"));
    let text = String::from_utf8_lossy(&pdf);
    assert_eq!(
        text.matches("/Type /Page\n").count()
            + text.matches("/Type /Page/").count()
            + text.matches("/Type /Page ").count(),
        1,
        "one page"
    );
    assert!(
        text.contains("/FontFile2") || text.contains("/FontFile"),
        "the font is embedded"
    );
}

#[test]
fn format_follows_the_flag_then_the_extension() {
    let p = |s: &str| PathBuf::from(s);
    assert_eq!(
        figure_path(Path::new("a/fig.svg"), Some(FigureFormat::Png)).unwrap(),
        (p("a/fig.png"), FigureFormat::Png)
    );
    assert_eq!(
        figure_path(Path::new("fig.PDF"), None).unwrap(),
        (p("fig.PDF"), FigureFormat::Pdf)
    );
    assert_eq!(
        figure_path(Path::new("fig"), None).unwrap(),
        (p("fig"), FigureFormat::Svg)
    );
    assert_eq!(
        figure_path(Path::new("fig.v2"), Some(FigureFormat::Pdf)).unwrap(),
        (p("fig.v2.pdf"), FigureFormat::Pdf)
    );
    assert!(figure_path(Path::new("fig.jpg"), None).is_err());
}

/// Runs `cablevib ARGS` and returns (status ok, stdout, stderr).
fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(BIN).args(args).output().expect("run cablevib");
    let s = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.success(), s(&out.stdout), s(&out.stderr))
}

#[test]
fn cli_writes_every_format_and_refuses_bad_ones_in_one_line() {
    let dir = std::env::temp_dir().join(format!("cablevib-figures-{}", std::process::id()));
    let out = dir.join("m");
    let out_s = out.to_string_lossy().into_owned();
    let base = [
        "map",
        "planar-paper",
        "--x=-1,1",
        "--y=-1,1",
        "--step",
        "0.5",
        "--quiet",
        "--out",
        &out_s,
    ];
    for (f, magic) in [
        ("png", &b"\x89PNG"[..]),
        ("pdf", &b"%PDF"[..]),
        ("svg", &b"<svg"[..]),
    ] {
        let (ok, _, err) = run(&[&base[..], &["--format", f]].concat());
        assert!(ok, "{err}");
        let bytes = std::fs::read(dir.join(format!("m.{f}"))).expect("figure written");
        assert!(bytes.starts_with(magic), "{f}");
    }
    let fig = dir.join("x.pdf").to_string_lossy().into_owned();
    let (ok, _, err) = run(&[&base[..], &["--svg", &fig]].concat());
    assert!(
        ok && std::fs::read(&fig)
            .map(|b| b.starts_with(b"%PDF"))
            .unwrap_or(false),
        "{err}"
    );
    // Mistakes: the reason on one line, first.
    let (ok, _, err) = run(&[&base[..], &["--format", "jpg"]].concat());
    let first = err.lines().next().unwrap_or("");
    assert!(
        !ok && first.contains("jpg") && first.contains("svg, png or pdf"),
        "{err}"
    );
    let bad = dir.join("x.jpg").to_string_lossy().into_owned();
    let (ok, _, err) = run(&[&base[..], &["--svg", &bad]].concat());
    assert!(
        !ok && err.trim().lines().count() == 1 && err.contains(".jpg"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
