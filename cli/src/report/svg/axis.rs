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

/// Log axes draw minor ticks (2..9 × 10^e) up to this many decades; beyond, they crowd.
const MINOR_DECADES: i32 = 6;

/// Tick positions (value, is_major) within the range: on a log axis every decade is major
/// (and labelled), on a linear axis a 1-2-2.5-5 step giving about 6 ticks.
pub(super) fn ticks(a: &Axis, r: (f64, f64)) -> Vec<(f64, bool)> {
    let mut t = Vec::new();
    if a.log {
        let (l, h) = (r.0.log10().floor() as i32, r.1.log10().ceil() as i32);
        for e in l..=h {
            let base = 10f64.powi(e);
            if base >= r.0 * (1.0 - 1e-9) && base <= r.1 * (1.0 + 1e-9) {
                t.push((base, true));
            }
            if h - l <= MINOR_DECADES {
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
    let Some(step) = linear_step(r) else {
        return t;
    };
    let mut v = (r.0 / step).ceil() * step;
    while v <= r.1 + step * 1e-9 {
        let vv = if v.abs() < step * 1e-9 { 0.0 } else { v };
        t.push((vv, true));
        v += step;
    }
    t
}

/// The step of a linear axis over `r`: 1, 2, 2.5 or 5 × 10^k, about 6 ticks.
fn linear_step(r: (f64, f64)) -> Option<f64> {
    let span = r.1 - r.0;
    if !(span > 0.0 && span.is_finite()) {
        return None;
    }
    let mag = 10f64.powf((span / 6.0).log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 7.5)
        .unwrap_or(10.0 * mag);
    Some(step)
}

/// Decades of a log axis whose labels are plain numbers (0.01 .. 1000); an axis reaching
/// beyond labels every decade as a power of ten.
const PLAIN_DECADES: std::ops::RangeInclusive<i32> = -2..=3;
/// Linear tick values at or above this magnitude are written as m×10^e.
const LINEAR_SCI_ABOVE: f64 = 1e5;

/// The labels of the major ticks `values` of axis `a` (range `r`), in one style per axis:
/// on a log axis all plain numbers or all powers of ten; on a linear axis all with the
/// decimals of the step, or all as m×10^e with one exponent (SVG markup, escaped).
pub(super) fn tick_labels(a: &Axis, r: (f64, f64), values: &[f64]) -> Vec<String> {
    if a.log {
        let exps: Vec<i32> = values.iter().map(|v| v.log10().round() as i32).collect();
        let plain = exps.iter().all(|e| PLAIN_DECADES.contains(e));
        return exps
            .iter()
            .zip(values)
            .map(|(&e, &v)| {
                if plain {
                    fmt_num(v)
                } else {
                    power_of_ten(1.0, 0, e)
                }
            })
            .collect();
    }
    let step = linear_step(r).unwrap_or(1.0);
    let top = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if top >= LINEAR_SCI_ABOVE {
        let e = top.log10().floor() as i32;
        let d = decimals(step / 10f64.powi(e));
        return values
            .iter()
            .map(|&v| power_of_ten(v / 10f64.powi(e), d, e))
            .collect();
    }
    let d = decimals(step);
    values
        .iter()
        .map(|&v| format!("{v:.d$}").replace('-', "−"))
        .collect()
}

/// Decimals that show a multiple of `step` exactly (2.5 needs one more than 2).
fn decimals(step: f64) -> usize {
    (0..=9)
        .find(|&d| {
            let s = step * 10f64.powi(d);
            (s - s.round()).abs() < 1e-6 * s.max(1.0)
        })
        .unwrap_or(9) as usize
}

/// `m×10^e` as SVG text (mantissa with `d` decimals; `10^e` alone when m = 1 and d = 0).
fn power_of_ten(m: f64, d: usize, e: i32) -> String {
    let sup = format!(
        r#"10<tspan dy="-6" font-size="9">{}</tspan>"#,
        super::escape(&e.to_string()).replace('-', "−")
    );
    if m == 1.0 && d == 0 {
        sup
    } else {
        format!("{}×{sup}", format!("{m:.d$}").replace('-', "−"))
    }
}
