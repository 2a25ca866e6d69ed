//! The chords and middle tensions of N equal elements on one catenary, all at once: the
//! per-cycle set-up of a sagged FEM chain.
//!
//! Element j runs from s_j = j·L0/N to s_j+1 (unstretched arclength). Its chord is
//! [`Catenary::chord_between_m`]`(s_j, s_j+1)` and its axial force
//! [`Catenary::tension_at_n`] at (j + ½)·L0/N. [`CatenaryElements::compute`] gives exactly
//! those numbers (bit for bit: the same operations in the same order), but
//!
//! - computes each node's V and T once (an element shares its nodes with its neighbours);
//! - runs the common case of every element, like-signed V at both nodes, the series of
//!   log1p(u)/u (u < 0.03) and every square in the normal range, as one loop without
//!   branches (selects only) that the compiler vectorises;
//! - recomputes the few other elements (the one holding the low point, u ≥ 0.03 on a slack
//!   cable, a vertical cable with H = 0, squares outside the normal range) by the scalar
//!   forms afterwards.

use super::catenary::{LOG1P_RATIO_SERIES, LOG1P_SERIES_BELOW};
use super::{Catenary, HYPOT_SQUARE_MAX, HYPOT_SQUARE_MIN};

/// Buffers for up to `capacity` elements (allocated once by [`CatenaryElements::new`];
/// `Default` holds none and does not allocate).
#[derive(Debug, Clone, Default)]
pub struct CatenaryElements {
    /// Node arclengths s_j, m (N + 1).
    s: Vec<f64>,
    /// Node V_j, N (N + 1).
    v: Vec<f64>,
    /// Node T_j, N (N + 1).
    t: Vec<f64>,
    /// Element chords: horizontal, m (N).
    x: Vec<f64>,
    /// Element chords: vertical, m (N).
    z: Vec<f64>,
    /// Element axial forces (tension at the middle), N (N).
    axial: Vec<f64>,
    /// 1.0 where the element takes the scalar forms (N).
    special: Vec<f64>,
    n: usize,
}

impl CatenaryElements {
    /// Room for up to `capacity` elements (the only allocation).
    pub fn new(capacity: usize) -> CatenaryElements {
        let cap = capacity.max(1);
        CatenaryElements {
            s: vec![0.0; cap + 1],
            v: vec![0.0; cap + 1],
            t: vec![0.0; cap + 1],
            x: vec![0.0; cap],
            z: vec![0.0; cap],
            axial: vec![0.0; cap],
            special: vec![0.0; cap],
            n: 0,
        }
    }

    /// Largest element count.
    pub fn capacity(&self) -> usize {
        self.x.len()
    }

    /// The `n_el` elements of `cat` (1 ≤ n_el ≤ capacity, else nothing is computed and
    /// false is returned). No allocation.
    pub fn compute(&mut self, cat: &Catenary, n_el: usize) -> bool {
        if n_el == 0 || n_el > self.capacity() {
            self.n = 0;
            return false;
        }
        self.n = n_el;
        self.vector_part(cat, n_el);
        self.scalar_fixups(cat, n_el);
        true
    }

    /// Element j's chord (x, z) in (h, up), m.
    #[inline]
    pub fn chord_m(&self, j: usize) -> [f64; 2] {
        [self.x[j], self.z[j]]
    }

    /// Element j's axial force, N.
    #[inline]
    pub fn axial_n(&self, j: usize) -> f64 {
        self.axial[j]
    }

    /// The nodes and every element by the common-case forms (`vector_body`), compiled for
    /// the widest vector unit the CPU has (the same operations: the results do not depend
    /// on it).
    fn vector_part(&mut self, cat: &Catenary, n_el: usize) {
        vector_dispatched(self, cat, n_el);
    }

    /// The marked elements by [`Catenary::chord_between_m`] and [`Catenary::tension_at_n`].
    fn scalar_fixups(&mut self, cat: &Catenary, n_el: usize) {
        let (l, n) = (cat.l0_m, n_el as f64);
        for j in 0..n_el {
            if self.special[j] != 0.0 {
                let [xj, zj] = cat.chord_between_m(self.s[j], self.s[j + 1]);
                self.x[j] = xj;
                self.z[j] = zj;
                self.axial[j] = cat.tension_at_n(l * (j as f64 + 0.5) / n);
            }
        }
    }
}

crate::simd::dispatch! {
    /// [`vector_body`] compiled for AVX-512F or AVX2 when the CPU has it (same results).
    fn vector_dispatched(
        e: &mut CatenaryElements,
        cat: &Catenary,
        n_el: usize,
    ) = vector_body;
    features ["avx512f", "avx2"];
    tiers vector_tier;
}

/// The nodes, then every element.
#[inline(always)]
fn vector_body(e: &mut CatenaryElements, cat: &Catenary, n_el: usize) {
    nodes(e, cat, n_el);
    common_body(e, cat, n_el);
}

/// s_j, V_j and T_j of every node (T by one square root; out of the normal range the
/// elements next to the node are recomputed by the scalar forms).
#[inline(always)]
fn nodes(e: &mut CatenaryElements, cat: &Catenary, n_el: usize) {
    let (l, n) = (cat.l0_m, n_el as f64);
    let (h, va, w) = (cat.h_n, cat.v_anchor_n, cat.w_n_m);
    let s = &mut e.s[..=n_el];
    let v = &mut e.v[..=n_el];
    let t = &mut e.t[..=n_el];
    for j in 0..=n_el {
        s[j] = l * j as f64 / n;
        v[j] = va + w * s[j];
        t[j] = (h * h + v[j] * v[j]).sqrt();
    }
}

/// Every element by the common-case forms, branch-free; `special` marks those that need
/// the scalar ones.
#[inline(always)]
fn common_body(e: &mut CatenaryElements, cat: &Catenary, n_el: usize) {
    let (l, n) = (cat.l0_m, n_el as f64);
    let (h, va, w, ea) = (cat.h_n, cat.v_anchor_n, cat.w_n_m, cat.ea_n);
    let (s, v, t) = (&e.s[..=n_el], &e.v[..=n_el], &e.t[..=n_el]);
    let x = &mut e.x[..n_el];
    let z = &mut e.z[..n_el];
    let axial = &mut e.axial[..n_el];
    let special = &mut e.special[..n_el];
    for j in 0..n_el {
        let (v1, v2, t1, t2) = (v[j], v[j + 1], t[j], t[j + 1]);
        let len = s[j + 1] - s[j];
        // branch_q of the catenary: one division on selected terms.
        let up = v1 >= 0.0;
        let num = if up {
            t1 + t2 + v1 + v2
        } else {
            t1 + t2 - v1 - v2
        };
        let den = (t1 + t2) * if up { t1 + v1 } else { t2 - v2 };
        let q = num / den;
        let u = w * len * q;
        let mut series = 0.0;
        for c in LOG1P_RATIO_SERIES.iter().rev() {
            series = c - u * series;
        }
        let xc = h * len * q * series;
        let xj = h * len / ea + xc;
        let sum_v = v1 + v2;
        let zj = 0.5 * len * sum_v / ea + len * sum_v / (t1 + t2);
        let sm = l * (j as f64 + 0.5) / n;
        let vm = va + w * sm;
        let sq_axial = h * h + vm * vm;
        axial[j] = sq_axial.sqrt();
        x[j] = xj;
        z[j] = zj;
        let sq1 = h * h + v1 * v1;
        let sq2 = h * h + v2 * v2;
        let normal = |q: f64| q > HYPOT_SQUARE_MIN && q < HYPOT_SQUARE_MAX;
        let ok = !(v1 < 0.0 && v2 > 0.0)
            & (u < LOG1P_SERIES_BELOW)
            & normal(sq1)
            & normal(sq2)
            & normal(sq_axial)
            & (h != 0.0);
        special[j] = if ok { 0.0 } else { 1.0 };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cat(l0_m: f64, w_n_m: f64, h_n: f64, v_anchor_n: f64) -> Catenary {
        Catenary {
            l0_m,
            ea_n: 3e6,
            w_n_m,
            h_n,
            v_anchor_n,
        }
    }

    /// Bit for bit the per-element scalar forms (`chord_between_m` between the nodes,
    /// `tension_at_n` at the middle), on profiles that exercise every branch: rising and
    /// falling, the low point inside one element, a slack cable whose elements need the
    /// logarithm (u ≥ 0.03), a vertical cable (H = 0), a weightless one, a tiny H whose
    /// squares leave the normal range, and element counts that are not a multiple of the
    /// vector width.
    #[test]
    fn elements_equal_the_scalar_forms_bit_for_bit() {
        let cases = [
            cat(10.0, 2.5, 150.0, 40.0),
            cat(10.0, 2.5, 150.0, -80.0),
            cat(10.0, 2.5, 150.0, -12.3),
            cat(200.0, 90.0, 1e3, -9e3),
            cat(30.0, 50.0, 5.0, -700.0),
            cat(5.0, 2.0, 0.0, 3.0),
            cat(5.0, 0.0, 100.0, 20.0),
            cat(5.0, 2.0, 1e-160, 1e-170),
            cat(180.0, 88.0, 2.0e5, 6.0e4),
        ];
        let mut e = CatenaryElements::new(400);
        let mut specials = 0;
        for c in &cases {
            for n in [1, 2, 3, 7, 40, 333, 400] {
                assert!(e.compute(c, n));
                specials += e.special[..n].iter().filter(|&&f| f != 0.0).count();
                for j in 0..n {
                    let s1 = c.l0_m * j as f64 / n as f64;
                    let s2 = c.l0_m * (j + 1) as f64 / n as f64;
                    let [x, z] = c.chord_between_m(s1, s2);
                    let axial = c.tension_at_n(c.l0_m * (j as f64 + 0.5) / n as f64);
                    let [xe, ze] = e.chord_m(j);
                    assert_eq!(
                        (xe.to_bits(), ze.to_bits(), e.axial_n(j).to_bits()),
                        (x.to_bits(), z.to_bits(), axial.to_bits()),
                        "{c:?} N = {n} element {j}: ({xe}, {ze}, {}) vs ({x}, {z}, {axial})",
                        e.axial_n(j)
                    );
                }
            }
        }
        assert!(specials > 0, "no element took the scalar forms");
        assert!(!e.compute(&cases[0], 401), "over capacity");
        assert!(!e.compute(&cases[0], 0), "no elements");
    }

    /// Every tier the CPU has (AVX-512F, AVX2) of the vector part against the portable
    /// body, bit for bit (tolerance 0: the same IEEE operations in the same order), on
    /// seeded random catenaries: lengths, weights and tensions over typical ranges and from
    /// 1e-150 to 1e150, V at the anchor of either sign, element counts 1 to 400.
    #[test]
    fn dispatched_tiers_equal_the_portable_body_bit_for_bit() {
        let mut rng = crate::simd::TestRng::new(0xca7e_0a11);
        let mut want = CatenaryElements::new(400);
        let mut got = CatenaryElements::new(400);
        let fields = |e: &CatenaryElements, n: usize| -> Vec<u64> {
            [&e.s, &e.v, &e.t]
                .iter()
                .flat_map(|a| a[..=n].iter())
                .chain(
                    [&e.x, &e.z, &e.axial, &e.special]
                        .iter()
                        .flat_map(|a| a[..n].iter()),
                )
                .map(|x| x.to_bits())
                .collect()
        };
        let mut tiers_run = 0;
        for trial in 0..600 {
            let sign = rng.sign();
            let c = if trial % 3 == 0 {
                cat(
                    rng.decades(-150.0, 150.0),
                    rng.decades(-150.0, 150.0),
                    rng.decades(-150.0, 150.0),
                    sign * rng.decades(-150.0, 150.0),
                )
            } else {
                cat(
                    rng.decades(0.0, 3.0),
                    rng.decades(-2.0, 2.0),
                    rng.decades(0.0, 6.0),
                    sign * rng.decades(0.0, 6.0),
                )
            };
            let n = 1 + (rng.next_u64() % 400) as usize;
            vector_tier(0, &mut want, &c, n).unwrap();
            for tier in 1..=2 {
                if vector_tier(tier, &mut got, &c, n).is_some() {
                    tiers_run += 1;
                    assert_eq!(
                        fields(&got, n),
                        fields(&want, n),
                        "tier {tier}: {c:?} N {n}"
                    );
                }
            }
            vector_dispatched(&mut got, &c, n);
            assert_eq!(fields(&got, n), fields(&want, n), "dispatched: {c:?} N {n}");
        }
        eprintln!("catenary elements: {tiers_run} tier runs beside the portable body");
    }
}
