//! The frequency response's files: the CSV of the receptance entries (real, imaginary,
//! magnitude, phase) and the Bode figure (magnitude on a log axis over phase) with the
//! natural frequencies marked.

use super::csv::{Column, Csv};
use super::svg::axis::Axis;
use super::svg::line_plot::{LinePlot, Mark, Series};
use nalgebra::Matrix6;
use num_complex::Complex64;
use serde_json::{json, Map};

/// Names of the end-effector's coordinates, translations first.
pub const COORDS: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

/// One computed response: the frequencies (Hz), the receptance at each (leading `dim`
/// block, m/N) and the entries (output, input) reported.
#[derive(Debug, Clone)]
pub struct FrfData {
    /// Frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// H at each frequency.
    pub h: Vec<Matrix6<Complex64>>,
    /// (output, input) coordinate pairs reported.
    pub pairs: Vec<(usize, usize)>,
    /// The natural frequencies in the band, Hz (marked on the figure).
    pub natural_hz: Vec<f64>,
}

/// The unit of entry (o, i): m/N, rad/N, m/(N·m) or rad/(N·m).
pub fn unit(o: usize, i: usize) -> &'static str {
    match (o < 3, i < 3) {
        (true, true) => "m/N",
        (false, true) => "rad/N",
        (true, false) => "m/(N*m)",
        (false, false) => "rad/(N*m)",
    }
}

fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.10e}")
    } else {
        "NaN".into()
    }
}

/// The CSV: `frequency_hz`, then per entry `h_<out>_<in>_re`, `_im`, `_abs`, `_phase_deg`.
pub fn frf_csv(d: &FrfData, meta: Map<String, serde_json::Value>) -> Csv {
    let mut cols = vec![Column::new("frequency_hz", "Hz", "excitation frequency")];
    for &(o, i) in &d.pairs {
        let (on, inn, u) = (COORDS[o], COORDS[i], unit(o, i));
        let what = format!("receptance: {on} response to a unit harmonic load along {inn}");
        cols.push(Column::new(
            format!("h_{on}_{inn}_re"),
            u,
            format!("{what}, real part"),
        ));
        cols.push(Column::new(
            format!("h_{on}_{inn}_im"),
            u,
            format!("{what}, imaginary part"),
        ));
        cols.push(Column::new(
            format!("h_{on}_{inn}_abs"),
            u,
            format!("{what}, magnitude"),
        ));
        cols.push(Column::new(
            format!("h_{on}_{inn}_phase_deg"),
            "deg",
            format!("{what}, phase (response behind load: negative)"),
        ));
    }
    let mut csv = Csv::new(cols, meta);
    for (f, h) in d.frequencies_hz.iter().zip(&d.h) {
        let mut row = vec![num(*f)];
        for &(o, i) in &d.pairs {
            let z = h[(o, i)];
            row.extend([
                num(z.re),
                num(z.im),
                num(z.norm()),
                num(z.arg().to_degrees()),
            ]);
        }
        csv.row(row);
    }
    csv
}

/// The sidecar's metadata of a response.
pub fn frf_meta(scene: &str, damping: &str, natural_hz: &[f64]) -> Map<String, serde_json::Value> {
    let mut m = Map::new();
    m.insert("scene".into(), json!(scene));
    m.insert("damping".into(), json!(damping));
    m.insert("natural_frequencies_hz".into(), json!(natural_hz));
    m
}

/// The Bode figure: |H| (log) over the phase (deg), one curve per entry, the natural
/// frequencies as dashed vertical lines.
pub fn bode_svg(d: &FrfData, title: &str, subtitle: &str, log_x: bool) -> String {
    let x_axis = |label: &str| {
        if log_x {
            Axis::log(label)
        } else {
            Axis::linear(label)
        }
    };
    let mut mag = LinePlot::new(title, x_axis("frequency [Hz]"), Axis::log("|H| [m/N]"));
    mag.subtitle = subtitle.into();
    let mut phase = LinePlot::new("", x_axis("frequency [Hz]"), Axis::linear("phase [deg]"));
    phase.height = 300.0;
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for &(o, i) in &d.pairs {
        let name = format!("H {}/{}", COORDS[o], COORDS[i]);
        let m: Vec<(f64, f64)> = d
            .frequencies_hz
            .iter()
            .zip(&d.h)
            .map(|(&f, h)| (f, h[(o, i)].norm()))
            .collect();
        for &(_, v) in &m {
            if v.is_finite() && v > 0.0 {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        let p: Vec<(f64, f64)> = d
            .frequencies_hz
            .iter()
            .zip(&d.h)
            .map(|(&f, h)| (f, h[(o, i)].arg().to_degrees()))
            .collect();
        mag.series.push(Series::new(&name, m, Mark::Line));
        phase.series.push(Series::new(&name, p, Mark::Line));
    }
    if hi > 0.0 {
        mag.y = Axis::log("|H| [m/N]").with_range(lo, hi);
    }
    phase.y = Axis::linear("phase [deg]").with_range(-180.0, 180.0);
    for (j, &f) in d.natural_hz.iter().enumerate() {
        let name = if j == 0 { "natural frequencies" } else { "" };
        if hi > 0.0 {
            mag.series
                .push(Series::new(name, vec![(f, lo), (f, hi)], Mark::Dashed).color("#999999"));
        }
        phase
            .series
            .push(Series::new("", vec![(f, -180.0), (f, 180.0)], Mark::Dashed).color("#999999"));
    }
    let (top, bottom) = (mag.to_svg(), phase.to_svg());
    let dims = |s: &str| -> (f64, f64) {
        let get = |k: &str| {
            s.split(&format!("{k}=\""))
                .nth(1)
                .and_then(|r| r.split('"').next())
                .and_then(|v| v.parse().ok())
                .unwrap_or(0.0)
        };
        (get("width"), get("height"))
    };
    let ((w1, h1), (w2, h2)) = (dims(&top), dims(&bottom));
    let mut out = super::svg::header(w1.max(w2), h1 + h2);
    out.push_str(&top.replacen("<svg ", "<svg x=\"0\" y=\"0\" ", 1));
    // The two plots' ids (their clip paths) must differ in one document.
    let bottom = bottom.replace("plotarea", "plotarea-phase");
    out.push_str(&bottom.replacen("<svg ", &format!("<svg x=\"0\" y=\"{h1:.0}\" "), 1));
    out.push_str("</svg>\n");
    out
}
