//! A chain whose anchor end is not fixed but held by another chain: the free cable's axial
//! chain in series with the cable hidden between the pulley and the winch drum
//! ([`crate::scene::HiddenCable`]). The pulley holds the junction transversely, so only
//! the axial chain is supported; the drum end of the hidden cable is fixed.
//!
//! **Two-port.** A uniform segment (N equal consistent-mass elements, or the continuous
//! bar) condensed onto its two ends has the dynamic stiffness [[s, t], [t, s]]: s is the
//! end stiffness with the other end fixed ([`super::Chain::eval`]'s s) and t the transfer.
//! Its determinant Δ = s² − t² is the same for every N: joining two symmetric two-ports of
//! determinant Δ at a node gives one of determinant Δ (expand the Schur complement), and a
//! single element has Δ = α² − β² = (2k − λm/6)(−λm/2) (α = k − λm/3, β = −k − λm/6). The
//! continuous bar (s = Kφ cot φ, t = −Kφ/sin φ) has Δ = −K²φ² = −λKM (K = S/L, M = μL).
//!
//! **Supported end.** With the hidden segment's end stiffness h(λ) (drum fixed) at the
//! junction, condensing the junction gives the free end's stiffness
//!
//! ```text
//!     s_eff = s − t²/(s + h) = (h s + Δ)/(s + h),
//! ```
//!
//! with no t and no cancellation (at λ = 0, Δ = 0: the series spring h s/(s + h)). The
//! Wittrick–Williams count of the supported chain (its far end held) is the free segment's
//! blocked count + the hidden segment's + [s + h < 0] (the junction's pivot).
//!
//! **Poles.** The supported chain's blocked eigenvalues interlace with the union of the two
//! segments' (Cauchy: they are the junction's eigenvalues with the junction released);
//! between two consecutive members of the union s + h falls from +∞ to −∞, so the j-th
//! blocked eigenvalue is the one root of s + h between the (j−1)-th and j-th members of the
//! union, found by safeguarded Newton ([`supported_pole`]).

use super::{chain_recurrence, continuous_string, eval_continuous, eval_discrete, ChainEval};
use crate::cable::ChainScalar;
use num_complex::Complex64;

/// Largest number of iterations of the pole search (bisection steps included): 1100
/// doublings reach any finite λ from 1e-300, and a safeguarded Newton halves its bracket
/// at least every other step.
const POLE_SEARCH_MAX_ITERATIONS: u32 = 1200;

/// One uniform segment of a supported chain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Discrete: element spring, N/m. Continuous: S/L, N/m.
    pub k: f64,
    /// Discrete: element mass, kg. Continuous: μL, kg.
    pub m: f64,
    /// Number of equal elements (≥ 1); 0 for the continuous bar.
    pub n_el: usize,
}

impl Segment {
    /// End stiffness (other end fixed), its derivative and blocked count at λ.
    #[inline]
    pub fn eval(&self, lambda: f64) -> ChainEval {
        if self.n_el == 0 {
            eval_continuous(self.k, self.m, lambda)
        } else {
            eval_discrete(self.k, self.m, self.n_el, lambda)
        }
    }

    /// The two-port's determinant Δ = s² − t² and dΔ/dλ (N²/m², N²/m² per rad²/s²), at a
    /// real or complex λ.
    #[inline]
    pub fn det<T: ChainScalar>(&self, lambda: T) -> (T, T) {
        let (k, m) = (self.k, self.m);
        if self.n_el == 0 {
            (-lambda * k * m, T::re(-k * m))
        } else {
            let a = T::re(2.0 * k) - lambda * m / 6.0;
            let b = lambda * -0.5 * m;
            (a * b, b * (-m / 6.0) - a * (0.5 * m))
        }
    }

    /// End stiffness and its derivative at a complex λ (the count is 0 there): the same
    /// recurrences as [`super::Chain::eval_at`].
    #[inline]
    pub fn eval_at(&self, lambda: Complex64) -> ChainEval<Complex64> {
        if self.n_el == 0 {
            continuous_string(self.k, self.m, lambda)
        } else {
            chain_recurrence(self.k, self.m, self.n_el, lambda)
        }
    }

    /// Static end stiffness, N/m: k/N (N springs in series), S/L for the bar.
    pub fn static_stiffness(&self) -> f64 {
        if self.n_el == 0 {
            self.k
        } else {
            self.k / self.n_el as f64
        }
    }

    /// Number of blocked eigenvalues (`usize::MAX / 4` for a continuous bar with mass).
    pub fn n_poles(&self) -> usize {
        if self.m <= 0.0 || self.k <= 0.0 {
            0
        } else if self.n_el == 0 {
            usize::MAX / 4
        } else {
            self.n_el - 1
        }
    }

    /// The j-th (1-based) blocked eigenvalue, rad²/s² (∞ past the last; −∞ for j = 0, the
    /// sentinel of [`supported_pole`]'s merge).
    pub fn pole(&self, j: usize) -> f64 {
        if j == 0 {
            return f64::NEG_INFINITY;
        }
        if j > self.n_poles() {
            return f64::INFINITY;
        }
        if self.n_el == 0 {
            let pj = j as f64 * std::f64::consts::PI;
            pj * pj * self.k / self.m
        } else {
            let th = j as f64 * std::f64::consts::PI / self.n_el as f64;
            let one_minus_c = 2.0 * (0.5 * th).sin().powi(2);
            6.0 * self.k * one_minus_c / (self.m * (2.0 + th.cos()))
        }
    }

    /// End mass with the other end fixed (the λ → −∞ limit of −s/λ), kg: m/3 + (m/6)q for
    /// N ≥ 2 consistent elements, m/3 for one, 0 for the bar.
    pub fn end_mass_kg(&self) -> f64 {
        if self.n_el == 0 || self.m <= 0.0 {
            0.0
        } else if self.n_el == 1 {
            self.m / 3.0
        } else {
            self.m / 3.0 + self.m / 6.0 * super::end_mass_q(self.n_el)
        }
    }
}

/// The free segment supported by the hidden one at λ: s_eff, s_eff' and the count.
#[inline]
pub fn eval_supported(free: &Segment, hidden: &Segment, lambda: f64) -> ChainEval {
    supported_from_parts(free, hidden, free.eval(lambda), hidden.eval(lambda), lambda)
}

/// [`eval_supported`] from the two segments' own evaluations at λ (`f` of `free`, `h` of
/// `hidden`, each with its far end fixed), however they were computed: the solver's batched
/// evaluations pass theirs here.
#[inline]
pub fn supported_from_parts(
    free: &Segment,
    hidden: &Segment,
    f: ChainEval,
    h: ChainEval,
    lambda: f64,
) -> ChainEval {
    let (dl, ddl) = free.det(lambda);
    let mut q = f.s + h.s;
    if q == 0.0 {
        // Exactly on a blocked eigenvalue: nudged as the uniform chain's recurrence does.
        q = f64::EPSILON * free.k.abs().max(hidden.k.abs()).max(1e-300);
    }
    let (s, ds) = combine(&f, &h, dl, ddl, q);
    ChainEval {
        s,
        ds,
        below: f.below + h.below + (q < 0.0) as u32,
    }
}

/// The supported chain at a complex λ (the damped frequency response): s_eff and s_eff'
/// by the same formula as [`eval_supported`], the count 0.
pub fn eval_supported_at(
    free: &Segment,
    hidden: &Segment,
    lambda: Complex64,
) -> ChainEval<Complex64> {
    let f = free.eval_at(lambda);
    let h = hidden.eval_at(lambda);
    let (dl, ddl) = free.det(lambda);
    let q = f.s + h.s;
    let (s, ds) = combine(&f, &h, dl, ddl, q);
    ChainEval { s, ds, below: 0 }
}

/// s_eff = (h s + Δ)/q and its derivative from the segments' values, q = s + h (one
/// formula for real and complex λ).
#[inline]
fn combine<T: ChainScalar>(f: &ChainEval<T>, h: &ChainEval<T>, dl: T, ddl: T, q: T) -> (T, T) {
    let dq = f.ds + h.ds;
    let num = h.s * f.s + dl;
    (
        num / q,
        (h.ds * f.s * f.s + h.s * h.s * f.ds + ddl * q - dl * dq) / (q * q),
    )
}

/// Static end stiffness of the supported chain, N/m: the two segments in series.
pub fn supported_static(free: &Segment, hidden: &Segment) -> f64 {
    let (s, h) = (free.static_stiffness(), hidden.static_stiffness());
    s * h / (s + h)
}

/// End mass of the supported chain (λ → −∞ limit of −s_eff/λ), kg: with M_s, M_h the
/// segments' end masses, lim t²/λ² = M_s² − m²/12 (discrete free segment of element mass
/// m; Δ/λ² → m²/12), so M = M_s − (M_s² − m²/12)/(M_s + M_h) = (M_s M_h + m²/12)/(M_s + M_h);
/// 0 for a continuous free segment.
pub fn supported_end_mass(free: &Segment, hidden: &Segment) -> f64 {
    if free.n_el == 0 || free.m <= 0.0 {
        return 0.0;
    }
    let (ms, mh) = (free.end_mass_kg(), hidden.end_mass_kg());
    (ms * mh + free.m * free.m / 12.0) / (ms + mh)
}

/// Number of blocked eigenvalues of the supported chain (`usize::MAX / 4` when one segment
/// is a bar with mass): both segments' and the junction's.
pub fn supported_n_poles(free: &Segment, hidden: &Segment) -> usize {
    let (a, b) = (free.n_poles(), hidden.n_poles());
    if a >= usize::MAX / 4 || b >= usize::MAX / 4 {
        return usize::MAX / 4;
    }
    let massive = free.m > 0.0 || hidden.m > 0.0;
    a + b + massive as usize
}

/// The j-th smallest (1-based) of the union of the two segments' blocked eigenvalues (∞
/// past the last): binary search on how many come from `free`. O(log j).
fn union_kth(free: &Segment, hidden: &Segment, j: usize) -> f64 {
    if j == 0 {
        return 0.0;
    }
    let (na, nb) = (free.n_poles(), hidden.n_poles());
    let (mut lo, mut hi) = (j.saturating_sub(nb), j.min(na));
    if lo > hi {
        return f64::INFINITY; // j is past both sets
    }
    // Largest i in [lo, hi] with free.pole(i) ≤ hidden.pole(j − i + 1).
    while lo < hi {
        let i = lo + (hi - lo).div_ceil(2);
        if free.pole(i) > hidden.pole(j - i + 1) {
            hi = i - 1;
        } else {
            lo = i;
        }
    }
    free.pole(lo).max(hidden.pole(j - lo)).max(0.0)
}

/// The j-th (1-based) blocked eigenvalue of the supported chain, rad²/s² (∞ past the last,
/// 0 for j = 0): the root of s + h between the (j−1)-th and j-th members of the union of the
/// segments' blocked eigenvalues, by Newton's method kept inside the sign bracket (bounded:
/// `POLE_SEARCH_MAX_ITERATIONS`).
pub fn supported_pole(free: &Segment, hidden: &Segment, j: usize) -> f64 {
    supported_pole_near(free, hidden, j, f64::NAN)
}

/// [`supported_pole`] with the search started at `hint` (rad²/s²) when it lies inside the
/// pole's bracket (a nearby pose's value: Newton then needs two or three steps instead of
/// the search from the bracket's middle); any other `hint` (NaN) starts in the middle. The
/// search and its stopping test are the same, so the result is the same root to the
/// search's tolerance (4ε relative), whatever the hint.
pub fn supported_pole_near(free: &Segment, hidden: &Segment, j: usize, hint: f64) -> f64 {
    if j == 0 {
        return 0.0;
    }
    if j > supported_n_poles(free, hidden) {
        return f64::INFINITY;
    }
    let a = union_kth(free, hidden, j - 1);
    let b = union_kth(free, hidden, j);
    if b <= a {
        return a; // coincident blocked eigenvalues of the two segments
    }
    let junction = |x: f64| {
        let (f, h) = (free.eval(x), hidden.eval(x));
        (f.s + h.s, f.ds + h.ds)
    };
    let (mut lo, mut hi) = (a, b);
    let mut it = 0u32;
    if !hi.is_finite() {
        // Past the last blocked eigenvalue of both discrete segments: s + h → −∞.
        hi = 2.0 * a.max(free.k / free.m.max(f64::MIN_POSITIVE)).max(1e-300);
        while junction(hi).0 >= 0.0 && it < POLE_SEARCH_MAX_ITERATIONS {
            lo = hi;
            hi *= 2.0;
            it += 1;
        }
    }
    let mut x = if hint > lo && hint < hi {
        hint
    } else {
        0.5 * (lo + hi)
    };
    while it < POLE_SEARCH_MAX_ITERATIONS {
        it += 1;
        let (g, dg) = junction(x);
        if g == 0.0 {
            return x;
        }
        if g > 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        if hi - lo <= 4.0 * f64::EPSILON * hi {
            break;
        }
        let newton = x - g / dg;
        let next = if newton > lo && newton < hi && dg < 0.0 {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - x).abs() <= 2.0 * f64::EPSILON * x {
            return next;
        }
        x = next;
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// The supported chain's K and M (far end fixed, the free end included last), dense.
    fn dense(free: &Segment, hidden: &Segment) -> (DMatrix<f64>, DMatrix<f64>) {
        // Nodes: drum (fixed) 0, hidden interior 1..nh−1, junction nh, free interior, end.
        let (nh, nf) = (hidden.n_el, free.n_el);
        let n = nh + nf; // DOFs: nodes 1 ..= nh + nf
        let mut k = DMatrix::zeros(n, n);
        let mut m = DMatrix::zeros(n, n);
        let mut add = |a: usize, b: usize, ke: f64, me: f64| {
            for (ia, na) in [a, b].into_iter().enumerate() {
                for (ib, nb) in [a, b].into_iter().enumerate() {
                    if na == 0 || nb == 0 {
                        continue;
                    }
                    let same = ia == ib;
                    k[(na - 1, nb - 1)] += if same { ke } else { -ke };
                    m[(na - 1, nb - 1)] += if same { me / 3.0 } else { me / 6.0 };
                }
            }
        };
        for e in 0..nh {
            add(e, e + 1, hidden.k, hidden.m);
        }
        for e in 0..nf {
            add(nh + e, nh + e + 1, free.k, free.m);
        }
        (k, m)
    }

    /// Condensation onto the last DOF of K − λM by a dense solve.
    fn condensed(k: &DMatrix<f64>, m: &DMatrix<f64>, lambda: f64) -> f64 {
        let a = k - m * lambda;
        let n = a.nrows();
        let aii = a.view((0, 0), (n - 1, n - 1)).into_owned();
        let aie = a.view((0, n - 1), (n - 1, 1)).into_owned();
        let x = aii.lu().solve(&aie).unwrap();
        a[(n - 1, n - 1)] - (aie.transpose() * x)[(0, 0)]
    }

    fn blocked_eigenvalues(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Vec<f64> {
        let n = k.nrows() - 1;
        let kk = k.view((0, 0), (n, n)).into_owned();
        let mm = m.view((0, 0), (n, n)).into_owned();
        let l = mm.cholesky().unwrap().l();
        let li = l.clone().try_inverse().unwrap();
        let c = &li * kk * li.transpose();
        let c = (&c + c.transpose()) * 0.5;
        let mut v: Vec<f64> = c.symmetric_eigenvalues().iter().copied().collect();
        v.sort_by(f64::total_cmp);
        v
    }

    /// Against a dense condensation and a dense eigen-solve of the same chain (independent
    /// of the two-port identity): s_eff to 1e-9 relative (the dense LU's rounding near
    /// poles), the count exactly, every blocked eigenvalue to 1e-10 relative.
    #[test]
    fn supported_chain_equals_the_dense_chain() {
        for (nf, nh, kh_rel, mh_rel) in [(10, 10, 0.7, 1.3), (4, 7, 3.0, 0.2), (1, 1, 1.0, 1.0)] {
            let free = Segment {
                k: 2.0e6,
                m: 0.03,
                n_el: nf,
            };
            let hidden = Segment {
                k: 2.0e6 * kh_rel,
                m: 0.03 * mh_rel,
                n_el: nh,
            };
            let (k, m) = dense(&free, &hidden);
            let poles = blocked_eigenvalues(&k, &m);
            assert_eq!(poles.len(), supported_n_poles(&free, &hidden));
            for (j, p) in poles.iter().enumerate() {
                let q = supported_pole(&free, &hidden, j + 1);
                assert!((q - p).abs() <= 1e-10 * p, "pole {}: {q} vs {p}", j + 1);
            }
            assert_eq!(
                supported_pole(&free, &hidden, poles.len() + 1),
                f64::INFINITY
            );
            let top = poles.last().copied().unwrap_or(1e8);
            for i in 0..300 {
                let lambda = top * 1.2 * (i as f64 / 300.0).powi(2) + 1e-3;
                let e = eval_supported(&free, &hidden, lambda);
                let d = condensed(&k, &m, lambda);
                assert!(
                    (e.s - d).abs() <= 1e-9 * (d.abs() + free.k),
                    "λ {lambda}: {} vs {d}",
                    e.s
                );
                let below = poles.iter().filter(|&&p| p < lambda).count() as u32;
                assert_eq!(e.below, below, "λ {lambda}");
                if lambda < 1e-6 * top {
                    continue; // a difference step there is lost in rounding
                }
                let h = 1e-7 * lambda;
                let fd = (eval_supported(&free, &hidden, lambda + h).s
                    - eval_supported(&free, &hidden, lambda - h).s)
                    / (2.0 * h);
                assert!(
                    (fd - e.ds).abs() <= 1e-4 * (fd.abs() + free.m),
                    "ds at {lambda} ({nf}, {nh}): {fd} vs {}",
                    e.ds
                );
            }
            // End mass: the λ → −∞ limit of −s/λ.
            let big = -1e18;
            let lim = -condensed(&k, &m, big) / big;
            let em = supported_end_mass(&free, &hidden);
            assert!((lim - em).abs() < 1e-6 * em, "{lim} vs {em}");
            let s0 = condensed(&k, &m, 0.0);
            assert!((supported_static(&free, &hidden) - s0).abs() < 1e-12 * s0);
        }
    }

    /// The continuous bar on a continuous bar: s_eff against a fine FEM of the same (O(1/N²)),
    /// and the poles against the transcendental equation of the two bars.
    #[test]
    fn supported_bar_equals_the_limit_of_the_chain() {
        let free = Segment {
            k: 1.0e6,
            m: 0.5,
            n_el: 0,
        };
        let hidden = Segment {
            k: 3.0e6,
            m: 0.2,
            n_el: 0,
        };
        let n = 400;
        let fem = |s: &Segment| Segment {
            k: s.k * n as f64,
            m: s.m / n as f64,
            n_el: n,
        };
        for j in 1..=4 {
            let p = supported_pole(&free, &hidden, j);
            let pf = supported_pole(&fem(&free), &fem(&hidden), j);
            assert!(
                (p - pf).abs() < 1e-4 * (j * j) as f64 * p,
                "{j}: {p} vs {pf}"
            );
            let e = eval_supported(&free, &hidden, p * (1.0 - 1e-9));
            assert_eq!(e.below, j as u32 - 1);
        }
        let lambda = 0.5 * supported_pole(&free, &hidden, 1);
        let (a, b) = (
            eval_supported(&free, &hidden, lambda),
            eval_supported(&fem(&free), &fem(&hidden), lambda),
        );
        assert!((a.s - b.s).abs() < 1e-5 * free.k, "{} vs {}", a.s, b.s);
    }
}
