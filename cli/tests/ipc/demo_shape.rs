//! `cablevib demo --shape zv|zvd|ei`: the replay shapes its poses online with the live
//! end-effector mode.
//!
//! - `demo --shape zv` (and zvd) on the paper's circle runs, and its summary has the shaping
//!   line with finite numbers: the mean design frequency within the range of the end-effector
//!   mode frequencies the summary reports (the shaper's design follows them through its
//!   filter, so its mean cannot leave their range), the delay half (ZV) or one (ZVD) period of
//!   that mean frequency (closed form, ζ = 0 on the undamped scene: 1/(2f), 1/f), at least one
//!   pose published unshaped before the first estimate (the first pose is sent before the
//!   service has estimated anything), and every pose either shaped or unshaped;
//! - a bad `--shape` is a one-line error of the option parser (exit 2), no panic.
//!
//! That each published pose is the shaper's output, and the trajectory's own bit for bit before
//! the first estimate, is the service crate's unit test (`demo_shape`), on the same type the
//! replay calls. The demo is a child process with a bounded wait (killed after it).

use crate::child::run;

/// The number that follows `key` in `line`.
fn number_after(line: &str, key: &str) -> f64 {
    let rest = &line[line
        .find(key)
        .unwrap_or_else(|| panic!("{key:?} in {line}"))
        + key.len()..];
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|e| panic!("{key:?} in {line}: {e}"))
}

#[test]
fn demo_shape_prints_a_finite_shaping_summary() {
    for (kind, periods) in [("zv", 0.5), ("zvd", 1.0)] {
        let o = run(&[
            "demo",
            "--seconds",
            "1.5",
            "--shape",
            kind,
            "--wait",
            "event",
        ]);
        let out = String::from_utf8_lossy(&o.stdout);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{kind}: {out}\n{err}");
        assert!(!err.contains("panicked"), "{err}");
        let ee = out
            .lines()
            .find(|l| l.contains("end-effector mode frequency:"))
            .unwrap_or_else(|| panic!("{out}"));
        let lo = number_after(ee, "frequency: ");
        let hi = number_after(ee, "… ");
        let line = out
            .lines()
            .find(|l| l.trim_start().starts_with("shaping:"))
            .unwrap_or_else(|| panic!("no shaping line: {out}"));
        assert!(line.contains(&format!("shaping: {kind} online")), "{line}");
        let mean = number_after(line, "mean design frequency ");
        let delay_ms = number_after(line, "adds ");
        let unshaped = number_after(line, "ms; ");
        let shaped = number_after(line, "end-effector mode, ");
        let dev = number_after(line, "from the unshaped ");
        for v in [mean, delay_ms, unshaped, shaped, dev] {
            assert!(v.is_finite(), "{line}");
        }
        // the summary's frequencies print to 1e-4 Hz
        assert!(mean >= lo - 1e-4 && mean <= hi + 1e-4, "{lo} {hi}: {line}");
        // the delay prints to 0.01 ms
        assert!((delay_ms - periods / mean * 1e3).abs() <= 0.006, "{line}");
        assert!(unshaped >= 1.0, "{line}");
        let sent = number_after(&out, "service: ");
        assert_eq!(unshaped + shaped, sent, "{line}");
        assert!(dev > 0.0, "{line}");
    }
}

#[test]
fn demo_bad_shape_is_a_one_line_error() {
    let o = run(&["demo", "--seconds", "0.1", "--shape", "zz"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("unknown shaper"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
