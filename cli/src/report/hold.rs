//! `cablevib demo --hold-f1 HZ --hold-csv PATH`: the two figures of the hold's record, f1 and
//! T_min against time, each beside the fixed T_min's.

use super::svg::{Axis, HLine, LinePlot, Mark, Series};

/// The record's columns the figures read.
const COLUMNS: [&str; 5] = ["t_s", "f1_hz", "setpoint_n", "fixed_t_min_n", "f1_fixed_hz"];

/// (f1 figure, T_min figure) of the record `csv` (the text `--hold-csv` wrote) for the
/// requirement `hold_hz`; `None` when a column is missing or a row does not parse.
pub fn hold_svgs(csv: &str, hold_hz: f64) -> Option<(String, String)> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next()?.split(',').collect();
    let idx: Vec<usize> = COLUMNS
        .iter()
        .map(|c| header.iter().position(|h| h == c))
        .collect::<Option<_>>()?;
    let mut rows = Vec::new();
    for l in lines {
        let v: Vec<&str> = l.split(',').collect();
        let get = |k: usize| v.get(idx[k])?.parse::<f64>().ok();
        rows.push([get(0)?, get(1)?, get(2)?, get(3)?, get(4)?]);
    }
    let series = |k: usize| rows.iter().map(|r| (r[0], r[k])).collect::<Vec<_>>();
    let fixed = rows.first().map_or(f64::NAN, |r| r[3]);
    let mut f1 = LinePlot::new(
        &format!("f1 under --hold-f1 {hold_hz} along the trajectory"),
        Axis::linear("t (s)"),
        Axis::linear("f1 (Hz)"),
    );
    f1.subtitle = "each ok estimate after the hold's first answer; the fixed T_min meets the \
                   requirement at every one of its poses"
        .into();
    f1.series
        .push(Series::new("f1 under the hold", series(1), Mark::Line));
    f1.series.push(Series::new(
        &format!("f1 at the fixed T_min {fixed:.2} N"),
        series(4),
        Mark::Dashed,
    ));
    f1.hlines.push(HLine {
        name: format!("requirement {hold_hz} Hz"),
        y: hold_hz,
        color: "#d62728".into(),
    });
    let mut t = LinePlot::new(
        &format!("T_min set-point under --hold-f1 {hold_hz}"),
        Axis::linear("t (s)"),
        Axis::linear("T_min (N)"),
    );
    t.subtitle = "the set-point published last before the service took each pose".into();
    t.series
        .push(Series::new("hold set-point", series(2), Mark::Line));
    t.hlines.push(HLine {
        name: format!("fixed T_min {fixed:.2} N"),
        y: fixed,
        color: "#7f7f7f".into(),
    });
    Some((f1.to_svg(), t.to_svg()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_both_figures_and_refuses_a_bad_record() {
        let csv = "t_s,pose_sequence,f1_hz,setpoint_n,sum_t2_n2,fixed_t_min_n,f1_fixed_hz,sum_t2_fixed_n2\n\
                   0.0,1,9.6,70,1,72.95,9.7,1\n0.001,2,9.61,70.5,1,72.95,9.69,1\n";
        let (a, b) = hold_svgs(csv, 9.5).unwrap();
        assert!(a.starts_with("<svg") || a.starts_with("<?xml"));
        assert!(
            a.contains("requirement 9.5 Hz"),
            "the requirement in the f1 figure"
        );
        // T_min is drawn with a subscript (rich text), so look for its value.
        assert!(
            b.contains("fixed T") && b.contains("72.95 N"),
            "the fixed T_min in the T_min figure"
        );
        assert!(hold_svgs("t_s,f1_hz\n0,1\n", 9.5).is_none());
        assert!(hold_svgs(&csv.replace("9.61", "x"), 9.5).is_none());
    }
}
