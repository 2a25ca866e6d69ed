//! One cable's elastic catenary: tensions, profile, tangent, sag and Irvine's λ², in the
//! cancellation-free forms of the module docs.

/// Below this u = w s q the factor log1p(u)/u is summed as its series Σ (−u)^k/(k + 1),
/// k ≤ 10 (truncation error u¹¹/12 < 2e-18), so that w = 0 and subnormal u need no special
/// case, and a short piece of cable (an element's chord) needs no logarithm.
pub(super) const LOG1P_SERIES_BELOW: f64 = 0.03;
/// 1/(k + 1), k = 0 ..= 10: the series' coefficients (alternating signs in the Horner form).
pub(super) const LOG1P_RATIO_SERIES: [f64; 11] = [
    1.0,
    1.0 / 2.0,
    1.0 / 3.0,
    1.0 / 4.0,
    1.0 / 5.0,
    1.0 / 6.0,
    1.0 / 7.0,
    1.0 / 8.0,
    1.0 / 9.0,
    1.0 / 10.0,
    1.0 / 11.0,
];

/// One cable's elastic catenary in its vertical plane (see module docs for coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Catenary {
    /// Unstretched length L0, m.
    pub l0_m: f64,
    /// Axial rigidity EA, N.
    pub ea_n: f64,
    /// Weight per unstretched length w ≥ 0, N/m.
    pub w_n_m: f64,
    /// Horizontal tension component H ≥ 0, N (constant along the cable).
    pub h_n: f64,
    /// Vertical component of the tension at the anchor (s = 0), N, positive up: V(s) = V_a + w s.
    pub v_anchor_n: f64,
}

/// log1p(u)/u for u ≥ 0, accurate to an ulp or two (1 at u = 0).
fn log1p_ratio(u: f64) -> f64 {
    if u < LOG1P_SERIES_BELOW {
        // Horner from the u¹⁰ term: 1 − u/2 + u²/3 − … + u¹⁰/11.
        LOG1P_RATIO_SERIES
            .iter()
            .rev()
            .fold(0.0, |acc, &c| c - u * acc)
    } else {
        u.ln_1p() / u
    }
}

/// The catenary part of x between the anchor and s (x minus the elastic H s/EA), m:
/// (H/w)[asinh(V/H) − asinh(V_a/H)] without cancellation. `ta`, `t` are T(0), T(s).
fn x_catenary(h: f64, va: f64, v: f64, ta: f64, t: f64, w: f64, s: f64) -> f64 {
    x_catenary_parts(h, va, v, ta, t, w, s)[0]
}

/// The catenary part of x between the anchor and s (as [`x_catenary`], m) and the same
/// divided by H, [asinh(V/H) − asinh(V_a/H)]/w, m/N (finite at H = 0 unless the low point
/// is inside, where it is +∞), from one logarithm (or one pair of asinh). `ta`, `t` are
/// T(0), T(s).
fn x_catenary_parts(h: f64, va: f64, v: f64, ta: f64, t: f64, w: f64, s: f64) -> [f64; 2] {
    if va < 0.0 && v > 0.0 {
        // Low point inside: two positive asinh terms, and w s > |V_a| + V > 0.
        let sum = (v / h).asinh() + (-va / h).asinh();
        // Vertical cable: no horizontal extent (the H → 0 limit of every branch).
        let x = if h == 0.0 { 0.0 } else { (h / w) * sum };
        return [x, sum / w];
    }
    let q = branch_q(va, v, ta, t);
    let ratio = log1p_ratio(w * s * q);
    let x = if h == 0.0 { 0.0 } else { h * s * q * ratio };
    [x, s * q * ratio]
}

/// The end point (x, z), m, the anchor and end tensions T_a, T_e, N, and
/// [asinh(V_e/H) − asinh(V_a/H)]/w, m/N, of catenary `c`, sharing the tensions and the
/// logarithm: bit for bit [`Catenary::end_point_m`], [`Catenary::tension_anchor_n`],
/// [`Catenary::tension_end_n`] and the x-part over H of the flexibility.
pub(super) fn end_parts(c: &Catenary) -> ([f64; 2], [f64; 2], f64) {
    let (h, va, w, s) = (c.h_n, c.v_anchor_n, c.w_n_m, c.l0_m);
    let v = c.v_at_n(s);
    let ta = super::hypot_fast(h, va);
    let t = super::hypot_fast(h, v);
    let [xc, over_h] = x_catenary_parts(h, va, v, ta, t, w, s);
    let x = h * s / c.ea_n + xc;
    let z = 0.5 * s * (va + v) / c.ea_n + z_catenary(va, v, ta, t, s);
    ([x, z], [ta, t], over_h)
}

/// q of the module docs for like-signed V_a, V (x_catenary = H s q log1p(w s q)/(w s q)).
fn branch_q(va: f64, v: f64, ta: f64, t: f64) -> f64 {
    if va >= 0.0 {
        (ta + t + va + v) / ((ta + t) * (ta + va))
    } else {
        (ta + t - va - v) / ((ta + t) * (t - v))
    }
}

/// The catenary part of z between the anchor and s, m: (T(s) − T_a)/w = s (V_a + V)/(T + T_a).
fn z_catenary(va: f64, v: f64, ta: f64, t: f64, s: f64) -> f64 {
    let sum_t = ta + t;
    if sum_t == 0.0 {
        // Zero tension at both points (H = V_a = w s = 0): the cable has no shape.
        return 0.0;
    }
    s * (va + v) / sum_t
}

impl Catenary {
    /// V(s) = V_a + w s, N.
    pub fn v_at_n(&self, s_m: f64) -> f64 {
        self.v_anchor_n + self.w_n_m * s_m
    }

    /// V at the end (s = L0), N.
    pub fn v_end_n(&self) -> f64 {
        self.v_at_n(self.l0_m)
    }

    /// T(s) = √(H² + V(s)²), N.
    pub fn tension_at_n(&self, s_m: f64) -> f64 {
        super::hypot_fast(self.h_n, self.v_at_n(s_m))
    }

    /// Anchor-end tension T_a = T(0), N.
    pub fn tension_anchor_n(&self) -> f64 {
        self.tension_at_n(0.0)
    }

    /// End-effector-end tension T_e = T(L0), N.
    pub fn tension_end_n(&self) -> f64 {
        self.tension_at_n(self.l0_m)
    }

    /// Smallest tension along the cable, N: H when the low point is inside (V_a < 0 < V_e),
    /// else the smaller end tension.
    pub fn tension_min_n(&self) -> f64 {
        if self.v_anchor_n < 0.0 && self.v_end_n() > 0.0 {
            self.h_n
        } else {
            self.tension_anchor_n().min(self.tension_end_n())
        }
    }

    /// (x, z) of the point at unstretched arclength s, m (stable forms).
    pub fn point_at_m(&self, s_m: f64) -> [f64; 2] {
        let (h, va, w) = (self.h_n, self.v_anchor_n, self.w_n_m);
        let v = self.v_at_n(s_m);
        let ta = super::hypot_fast(h, va);
        let t = super::hypot_fast(h, v);
        let x = h * s_m / self.ea_n + x_catenary(h, va, v, ta, t, w, s_m);
        let z = 0.5 * s_m * (va + v) / self.ea_n + z_catenary(va, v, ta, t, s_m);
        [x, z]
    }

    /// The chord from the point at s1 to the point at s2 ≥ s1 (unstretched arclengths), m:
    /// (x, z)(s2) − (x, z)(s1) by the same closed forms with the point at s1 as the anchor,
    /// so no cancellation between two absolute positions (an element's chord in `fem`).
    pub fn chord_between_m(&self, s1_m: f64, s2_m: f64) -> [f64; 2] {
        let (h, w) = (self.h_n, self.w_n_m);
        let (v1, v2) = (self.v_at_n(s1_m), self.v_at_n(s2_m));
        let (t1, t2) = (super::hypot_fast(h, v1), super::hypot_fast(h, v2));
        let l = s2_m - s1_m;
        let x = h * l / self.ea_n + x_catenary(h, v1, v2, t1, t2, w, l);
        let z = 0.5 * l * (v1 + v2) / self.ea_n + z_catenary(v1, v2, t1, t2, l);
        [x, z]
    }

    /// (x, z) of the end point (s = L0), m.
    pub fn end_point_m(&self) -> [f64; 2] {
        self.point_at_m(self.l0_m)
    }

    /// Unit tangent (cos, sin) in (h, up) toward increasing s: (H, V(s))/T(s). At a point of
    /// zero tension (a slack point) the tangent is undefined; (0, 1) is returned there.
    pub fn tangent_at(&self, s_m: f64) -> [f64; 2] {
        let v = self.v_at_n(s_m);
        let t = super::hypot_fast(self.h_n, v);
        if t > 0.0 {
            [self.h_n / t, v / t]
        } else {
            [0.0, 1.0]
        }
    }

    /// Unstretched arclength where the tangent is parallel to the chord (V(s*) = H Z/X),
    /// clamped to [0, L0]; `None` for a straight profile (w = 0, H = 0 or no span).
    fn s_parallel_to_chord_m(&self, chord: [f64; 2]) -> Option<f64> {
        let [x, z] = chord;
        if !(self.w_n_m > 0.0 && self.h_n > 0.0 && x > 0.0) {
            return None;
        }
        let s = (self.h_n * (z / x) - self.v_anchor_n) / self.w_n_m;
        Some(s.clamp(0.0, self.l0_m))
    }

    /// Largest distance of the profile from its chord, m (0 for a straight cable). The
    /// distance is |X z − Z x|/L at the point whose tangent is parallel to the chord; its
    /// absolute error is a few ulps of the chord length L.
    pub fn sag_m(&self) -> f64 {
        let end = self.end_point_m();
        let Some(s) = self.s_parallel_to_chord_m(end) else {
            return 0.0;
        };
        let len = end[0].hypot(end[1]);
        if !(len > 0.0) {
            return 0.0;
        }
        let [x, z] = self.point_at_m(s);
        (end[0] * z - end[1] * x).abs() / len
    }

    /// Irvine's λ² (dimensionless), inclined-chord form (module docs):
    /// λ² = (w X²/(H L))² · X EA/(H L_e), L_e = L (1 + 8 (d/L)²), d = [`Catenary::sag_m`];
    /// 0 for a vertical cable (H = 0 or span 0), where the weight is along the chord.
    pub fn irvine_lambda2(&self) -> f64 {
        let [x, z] = self.end_point_m();
        let len = super::hypot_fast(x, z);
        if !(self.h_n > 0.0 && x > 0.0 && len > 0.0) {
            return 0.0;
        }
        let d = self.sag_m() / len;
        let l_e = len * (1.0 + 8.0 * d * d);
        let a = self.w_n_m * x * x / (self.h_n * len);
        a * a * x * self.ea_n / (self.h_n * l_e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cat(l0: f64, ea: f64, w: f64, h: f64, va: f64) -> Catenary {
        Catenary {
            l0_m: l0,
            ea_n: ea,
            w_n_m: w,
            h_n: h,
            v_anchor_n: va,
        }
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    /// The textbook (cancelling) formulas, evaluated where they are well conditioned
    /// (w L0 comparable to T): an independent transcription of Irvine's equations.
    fn naive(c: &Catenary, s: f64) -> [f64; 2] {
        let (h, va, w, ea) = (c.h_n, c.v_anchor_n, c.w_n_m, c.ea_n);
        let v = va + w * s;
        let x = h * s / ea + (h / w) * ((v / h).asinh() - (va / h).asinh());
        let z = (va * s + w * s * s / 2.0) / ea + (h.hypot(v) - h.hypot(va)) / w;
        [x, z]
    }

    /// Every branch (low point before, inside, after; anchor above or below) agrees with
    /// the textbook forms where these lose at most ~10 ulps (w L0 ≈ T): tolerance 1e-13.
    #[test]
    fn stable_forms_equal_the_textbook_forms_where_both_are_accurate() {
        for &(h, va) in &[
            (50.0, 20.0),
            (50.0, -200.0),
            (50.0, -60.0),
            (5.0, -30.0),
            (80.0, 0.0),
        ] {
            let c = cat(3.0, 1e5, 40.0, h, va);
            for k in 0..=6 {
                let s = 0.5 * k as f64;
                let a = c.point_at_m(s);
                let b = naive(&c, s);
                for j in 0..2 {
                    assert!(
                        (a[j] - b[j]).abs() <= 1e-13 * (1.0 + b[j].abs()),
                        "h {h} va {va} s {s}: {a:?} vs {b:?}"
                    );
                }
            }
        }
    }

    /// w = 0: the straight stretched cable, x = s(1 + T/EA) H/T, z = s(1 + T/EA) V/T, to a
    /// few ulps (tolerance 4e-16 relative), also for H = 0 and V < 0.
    #[test]
    fn weightless_cable_is_straight() {
        for &(h, v) in &[
            (30.0, 40.0),
            (30.0, -40.0),
            (0.0, -50.0),
            (0.0, 50.0),
            (50.0, 0.0),
        ] {
            let c = cat(2.0, 1e4, 0.0, h, v);
            let t = h.hypot(v);
            let stretched = 2.0 * (1.0 + t / 1e4);
            let p = c.end_point_m();
            assert!(
                (p[0] - stretched * h / t).abs() <= 4e-16 * stretched,
                "{p:?}"
            );
            assert!(
                (p[1] - stretched * v / t).abs() <= 4e-16 * stretched,
                "{p:?}"
            );
            assert_eq!(c.sag_m(), 0.0);
            assert_eq!(c.tension_min_n(), t);
        }
    }

    /// Composite Simpson quadrature over [s1, s2] (n even intervals) of the profile's
    /// integrand (1 + T/EA)(H, V)/T of a cable with EA = 1e4 N: an independent formulation
    /// of the chord between two points.
    fn simpson_chord(w: f64, h: f64, va: f64, s1: f64, s2: f64, n: usize) -> [f64; 2] {
        let dx = (s2 - s1) / n as f64;
        let f = |s: f64| {
            let v = va + w * s;
            let t = h.hypot(v);
            let k = 1.0 + t / 1e4;
            [k * h / t, k * v / t]
        };
        let mut acc = [0.0; 2];
        for i in 0..=n {
            let wt = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let g = f(s1 + i as f64 * dx);
            acc[0] += wt * g[0] * dx / 3.0;
            acc[1] += wt * g[1] * dx / 3.0;
        }
        acc
    }

    /// The profile is ∫ (1 + T/EA)(H, V)/T ds: composite Simpson quadrature of that
    /// integrand (an independent formulation) on 20,000 intervals (error ~ h⁴ f⁗ below 1e-15
    /// relative for these smooth integrands) agrees to 1e-13 relative to the chord, for a
    /// tiny weight (w L0/T = 1e-9, where the textbook form has lost 9 digits), a heavy one,
    /// and a low point inside.
    #[test]
    fn profile_equals_the_quadrature_of_its_tangent() {
        for &(w, h, va) in &[
            (25e-9, 30.0, 40.0),
            (25e-9, 30.0, -40.0),
            (20.0, 30.0, -25.0),
            (20.0, 3.0, 5.0),
        ] {
            let c = cat(2.0, 1e4, w, h, va);
            let acc = simpson_chord(w, h, va, 0.0, 2.0, 20_000);
            let p = c.end_point_m();
            let len = acc[0].hypot(acc[1]);
            for j in 0..2 {
                assert!(
                    (p[j] - acc[j]).abs() < 1e-13 * len,
                    "w {w} h {h} va {va}: {p:?} vs {acc:?}"
                );
            }
        }
    }

    /// An element's chord (`chord_between_m`, the closed forms from a point inside the
    /// cable) equals the composite-Simpson quadrature of (1 + T/EA)(H, V)/T over its piece
    /// (an independent formulation, 2,000 intervals: error far below 1e-15 relative) to
    /// 1e-14 of its length, for pieces of 1/40 and 1/3 of the cable before, across and after
    /// the low point, a tiny weight, a heavy cable and a vertical one.
    #[test]
    fn element_chord_equals_the_quadrature_of_its_tangent() {
        for &(w, h, va) in &[
            (25e-9, 30.0, 40.0),
            (25e-9, 30.0, -40.0),
            (20.0, 30.0, -25.0),
            (20.0, 3.0, 5.0),
            (10.0, 0.0, -100.0),
        ] {
            let c = cat(2.0, 1e4, w, h, va);
            for &(s1, s2) in &[
                (0.0, 0.05),
                (1.2, 1.25),
                (1.95, 2.0),
                (0.5, 1.1666),
                (1.0, 2.0),
            ] {
                let acc = simpson_chord(w, h, va, s1, s2, 2_000);
                let got = c.chord_between_m(s1, s2);
                let len = acc[0].hypot(acc[1]);
                for j in 0..2 {
                    assert!(
                        (got[j] - acc[j]).abs() <= 1e-14 * len,
                        "w {w} h {h} va {va} [{s1}, {s2}]: {got:?} vs {acc:?}"
                    );
                }
            }
        }
    }

    /// A vertical rope (H = 0) hanging from its anchor above (V < 0 all along): the end is
    /// straight below, z(L0) = −(L0 + (T_a L0 − w L0²/2)/EA) with T_a = −V_a (closed form of
    /// ∫(1 + T/EA) ds, T(s) = T_a − w s); anchor below (V > 0): z = L0 + (V_a L0 + w L0²/2)/EA.
    #[test]
    fn vertical_cable_hangs_straight() {
        let (l0, ea, w) = (3.0, 2e4, 10.0);
        let above = cat(l0, ea, w, 0.0, -100.0);
        let p = above.end_point_m();
        let z = -(l0 + (100.0 * l0 - w * l0 * l0 / 2.0) / ea);
        assert_eq!(p[0], 0.0);
        assert!(rel(p[1], z) < 1e-15, "{p:?} vs {z}");
        assert_eq!(above.tension_end_n(), 70.0);
        assert_eq!(above.tension_min_n(), 70.0);
        assert_eq!(above.tangent_at(1.0), [0.0, -1.0]);
        let below = cat(l0, ea, w, 0.0, 40.0);
        let q = below.end_point_m();
        let z = l0 + (40.0 * l0 + w * l0 * l0 / 2.0) / ea;
        assert!(rel(q[1], z) < 1e-15, "{q:?} vs {z}");
        assert_eq!(below.tension_min_n(), 40.0);
        assert_eq!(below.sag_m(), 0.0);
        assert_eq!(below.irvine_lambda2(), 0.0);
    }

    /// Inextensible symmetric catenary z = a(cosh(x/a) − cosh(X/2a)) … with a = H/w:
    /// arclength from the low point is a sinh(x/a). Level span with V_a = −w L0/2: the
    /// span is 2a asinh(L0/(2a)), sag a(cosh(X/(2a)) − 1), minimum tension H (low point
    /// inside). Tolerance 1e-13 relative (EA = 1e15 leaves an elastic term 1e-13 below).
    #[test]
    fn level_inextensible_catenary_matches_cosh() {
        let (l0, w, h) = (10.0, 2.0, 7.0);
        let c = cat(l0, 1e15, w, h, -w * l0 / 2.0);
        let a = h / w;
        let span = 2.0 * a * (l0 / (2.0 * a)).asinh();
        let p = c.end_point_m();
        assert!(rel(p[0], span) < 1e-13, "{p:?} vs {span}");
        assert!(p[1].abs() < 1e-13 * l0, "{p:?}");
        let sag = a * ((span / (2.0 * a)).cosh() - 1.0);
        assert!(rel(c.sag_m(), sag) < 1e-13, "{} vs {sag}", c.sag_m());
        assert_eq!(c.tension_min_n(), h);
        // The profile lies on the cosh curve through the two ends.
        for k in 1..10 {
            let [x, z] = c.point_at_m(k as f64);
            let cosh_z = a * (((x - span / 2.0) / a).cosh() - (span / (2.0 * a)).cosh());
            assert!((z - cosh_z).abs() < 1e-13 * l0, "s {k}: {z} vs {cosh_z}");
        }
        let t = c.tangent_at(l0);
        assert!((t[0].hypot(t[1]) - 1.0).abs() < 1e-15);
        assert!(t[1] > 0.0);
    }
}
