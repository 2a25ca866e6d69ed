//! The one CSV writer of the commands: optional `#` comment line, header, rows; and the
//! number formats of their columns (NaN for a value the estimator did not give).

use crate::scene::Scene;
use crate::study::points::PointResult;
use std::fmt::Write as _;

/// A CSV document being written.
#[derive(Debug, Clone, Default)]
pub struct Csv {
    text: String,
}

impl Csv {
    /// A document starting with `# comment` (when given) and the `header` line.
    pub fn new(comment: Option<&str>, header: &str) -> Csv {
        let mut text = String::new();
        if let Some(c) = comment {
            let _ = writeln!(text, "# {c}");
        }
        let _ = writeln!(text, "{header}");
        Csv { text }
    }
    /// Append one row (the fields already joined by commas).
    pub fn row(&mut self, fields: &str) {
        self.text.push_str(fields);
        self.text.push('\n');
    }
    /// The document.
    pub fn into_string(self) -> String {
        self.text
    }
}

/// The start of a command's CSV comment: `cablevib COMMAND: scene NAME, model KIND x N`.
pub fn scene_comment(command: &str, s: &Scene) -> String {
    format!(
        "cablevib {command}: scene {}, model {} x {}",
        s.name,
        s.model.element.as_str(),
        s.model.elements_per_cable
    )
}

/// A finite value in scientific notation with 8 decimals, else `NaN`.
pub fn num(x: f64) -> String {
    num_p(x, 8)
}

/// A finite value in scientific notation with `digits` decimals, else `NaN`.
pub fn num_p(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$e}")
    } else {
        "NaN".into()
    }
}

/// CSV header of [`PointResult`] rows for a scene with `n` cables.
pub fn point_header(n: usize) -> String {
    let mut h = String::from(
        "x_m,y_m,z_m,t_min_n,status,f1_hz,ee_mode_hz,f1_ee_participation,ee_mode_participation",
    );
    for i in 0..n {
        let _ = write!(h, ",tension{}_n", i + 1);
    }
    h
}

/// The fields of one [`PointResult`] row (see [`point_header`]).
pub fn point_fields(r: &PointResult) -> String {
    let e = &r.estimate;
    let mut s = format!(
        "{},{},{},{},{},{},{},{},{}",
        r.position_m.x,
        r.position_m.y,
        r.position_m.z,
        r.t_min_n,
        e.status.as_str(),
        num(e.f1_hz),
        num(e.ee_mode_hz),
        num_p(e.f1_ee_participation, 4),
        num_p(e.ee_mode_participation, 4)
    );
    for t in e.tensions() {
        let _ = write!(s, ",{}", num_p(*t, 6));
    }
    s
}
