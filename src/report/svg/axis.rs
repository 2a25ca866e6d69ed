//! Plot axes: linear or logarithmic ranges, the data-to-pixel mapping and tick marks.

use super::fmt_num;

/// One plot axis.
#[derive(Debug, Clone, Default)]
pub struct Axis {
    /// Label under / beside the axis (unit in brackets by convention).
    pub label: String,
    /// Logarithmic (base 10) axis; non-positive values are not drawn.
    pub log: bool,
    /// Fixed range; `None` fits the data (with a small margin on linear axes).
    pub range: Option<(f64, f64)>,
}

impl Axis {
    /// A linear axis fitted to the data.
    pub fn linear(label: &str) -> Axis {
        Axis {
            label: label.into(),
            log: false,
            range: None,
        }
    }
    /// A log axis fitted to the data.
    pub fn log(label: &str) -> Axis {
        Axis {
            label: label.into(),
            log: true,
            range: None,
        }
    }
    /// With a fixed range.
    pub fn with_range(mut self, lo: f64, hi: f64) -> Axis {
        self.range = Some((lo, hi));
        self
    }
}

pub(super) fn fit_range(a: &Axis, v: &[f64]) -> (f64, f64) {
    if let Some(r) = a.range {
        return r;
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return if a.log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if a.log {
        let (l, h) = (lo.log10().floor(), hi.log10().ceil());
        let h = if h <= l { l + 1.0 } else { h };
        (10f64.powf(l), 10f64.powf(h))
    } else if hi > lo {
        let m = 0.05 * (hi - lo);
        (lo - m, hi + m)
    } else {
        let m = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
        (lo - m, hi + m)
    }
}

pub(super) struct Mapper {
    log: bool,
    d0: f64,
    d1: f64,
    p0: f64,
    p1: f64,
}

impl Mapper {
    pub(super) fn new(a: &Axis, r: (f64, f64), p0: f64, p1: f64) -> Mapper {
        let (d0, d1) = if a.log {
            (
                r.0.max(f64::MIN_POSITIVE).log10(),
                r.1.max(f64::MIN_POSITIVE).log10(),
            )
        } else {
            r
        };
        let d1 = if d1 > d0 { d1 } else { d0 + 1.0 };
        Mapper {
            log: a.log,
            d0,
            d1,
            p0,
            p1,
        }
    }
    pub(super) fn map(&self, v: f64) -> f64 {
        let v = if self.log { v.log10() } else { v };
        self.p0 + (v - self.d0) / (self.d1 - self.d0) * (self.p1 - self.p0)
    }
}

/// Tick positions (value, is_major) within the range.
pub(super) fn ticks(a: &Axis, r: (f64, f64)) -> Vec<(f64, bool)> {
    let mut t = Vec::new();
    if a.log {
        let (l, h) = (r.0.log10().floor() as i32, r.1.log10().ceil() as i32);
        let decades = (h - l).max(1);
        let every = (decades as f64 / 8.0).ceil().max(1.0) as i32;
        for e in l..=h {
            let base = 10f64.powi(e);
            if base >= r.0 * (1.0 - 1e-9) && base <= r.1 * (1.0 + 1e-9) && (e - l) % every == 0 {
                t.push((base, true));
            }
            if decades <= 6 {
                for k in 2..10 {
                    let v = base * k as f64;
                    if v > r.0 && v < r.1 {
                        t.push((v, false));
                    }
                }
            }
        }
        return t;
    }
    let span = r.1 - r.0;
    if !(span > 0.0 && span.is_finite()) {
        return t;
    }
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 7.5)
        .unwrap_or(10.0 * mag);
    let mut v = (r.0 / step).ceil() * step;
    while v <= r.1 + step * 1e-9 {
        let vv = if v.abs() < step * 1e-9 { 0.0 } else { v };
        t.push((vv, true));
        v += step;
    }
    t
}

pub(super) fn tick_label(a: &Axis, v: f64) -> String {
    if a.log {
        let e = v.log10().round() as i32;
        if (-2..=3).contains(&e) {
            return fmt_num(v);
        }
        return format!(r#"10<tspan dy="-6" font-size="9">{e}</tspan>"#);
    }
    fmt_num(v)
}
