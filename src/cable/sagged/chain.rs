//! The sagged FEM chain's data: per-element in-plane 2 × 2 and out-of-plane stiffness in
//! buffers sized once, filled from a profile without allocating.

use super::supported::SagSupport;
use super::{SagChainError, SagChainEval};
use crate::elastic_catenary::{Catenary, CatenaryElements};
use num_complex::Complex64;

/// One element of a sagged chain (element j runs from node j to node j + 1; node 0 is the
/// anchor), as the dense reference assembles it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SagElement {
    /// Unit chord (cos, sin) in (h, up), from the anchor-side node to the other.
    pub chord: [f64; 2],
    /// Unstretched length l0, m.
    pub l0_m: f64,
    /// Chord length l_j between the element's nodes on the profile, m.
    pub chord_m: f64,
    /// Axial force N_j = T at the element's middle, N.
    pub axial_n: f64,
    /// Axial stiffness EA/l0, N/m.
    pub k_axial_n_m: f64,
    /// Element mass μ l0, kg (consistent mass (m/6)[2 1; 1 2] per direction).
    pub mass_kg: f64,
    /// In-plane stiffness (EA/l0) c cᵀ + (N_j/l_j)(I − c cᵀ) as [a, b, c], N/m, (h, up).
    pub k_in: [f64; 3],
    /// Out-of-plane stiffness N_j/l_j, N/m.
    pub k_out: f64,
}

/// One sagged cable as a chain of N FEM elements on its static profile (see the module
/// docs). Built once with a capacity; [`SagChain::set_profile`] (or `set_fem`) refills it
/// in place; [`SagChain::eval`] reads it.
#[derive(Debug, Clone)]
pub struct SagChain {
    pub(super) k_in: Vec<[f64; 3]>,
    pub(super) k_out: Vec<f64>,
    chord: Vec<[f64; 2]>,
    chord_m: Vec<f64>,
    axial_n: Vec<f64>,
    capacity: usize,
    /// Element mass μ l0, kg.
    pub(super) mass_kg: f64,
    l0_m: f64,
    /// EA/l0, N/m.
    k_axial: f64,
    /// A pivot that is exactly singular is moved by this much, N/m.
    pub(super) nudge: f64,
    /// Scratch of `set_fem`: the elements' chords and tensions on the catenary.
    elements: CatenaryElements,
    /// The cable behind the anchor (its pulley), when the anchor node is not fixed.
    pub(super) support: Option<SagSupport>,
}

impl SagChain {
    /// An empty chain able to hold up to `n_el_max` elements (the only allocation).
    pub fn new(n_el_max: usize) -> SagChain {
        let cap = n_el_max.max(1);
        SagChain {
            k_in: Vec::with_capacity(cap),
            k_out: Vec::with_capacity(cap),
            chord: Vec::with_capacity(cap),
            chord_m: Vec::with_capacity(cap),
            axial_n: Vec::with_capacity(cap),
            capacity: cap,
            mass_kg: 0.0,
            l0_m: 0.0,
            k_axial: 0.0,
            nudge: 0.0,
            elements: CatenaryElements::new(cap),
            support: None,
        }
    }

    /// Fill the chain from a profile: `n_el` equal elements of the unstretched length
    /// `l0_total_m`, axial rigidity `ea_n`, mass per unstretched length `mu_kg_m`; node j
    /// at `point(s_j)` ((x, z) in (h, up), m, s_j = j·L0/N, node 0 the anchor) and axial
    /// force `tension(s)` (N) at each element's middle. No allocation. On error the chain
    /// is left empty (0 elements).
    pub fn set_profile(
        &mut self,
        ea_n: f64,
        mu_kg_m: f64,
        l0_total_m: f64,
        n_el: usize,
        point: impl Fn(f64) -> [f64; 2],
        tension: impl Fn(f64) -> f64,
    ) -> Result<(), SagChainError> {
        let s = |j: usize| l0_total_m * j as f64 / n_el as f64;
        let element = |j: usize| {
            let (a, b) = (point(s(j)), point(s(j + 1)));
            let axial = tension(l0_total_m * (j as f64 + 0.5) / n_el as f64);
            ([b[0] - a[0], b[1] - a[1]], axial)
        };
        self.fill(ea_n, mu_kg_m, l0_total_m, n_el, element)
    }

    /// As `set_profile`, with element j's chord ((x, z), m) and axial force (N) from
    /// `element(j)`.
    fn fill(
        &mut self,
        ea_n: f64,
        mu_kg_m: f64,
        l0_total_m: f64,
        n_el: usize,
        element: impl Fn(usize) -> ([f64; 2], f64),
    ) -> Result<(), SagChainError> {
        self.clear();
        if n_el == 0 || n_el > self.capacity {
            return Err(SagChainError::ElementCount {
                n_el,
                capacity: self.capacity,
            });
        }
        for (name, value, ok) in [
            ("ea_n", ea_n, ea_n > 0.0),
            ("mu_kg_m", mu_kg_m, mu_kg_m >= 0.0),
            ("l0_m", l0_total_m, l0_total_m > 0.0),
        ] {
            if !(ok && value.is_finite()) {
                return Err(SagChainError::BadInput { name, value });
            }
        }
        let l0 = l0_total_m / n_el as f64;
        let k_axial = ea_n / l0;
        let mut k_max = 0.0f64;
        for j in 0..n_el {
            let ([dx, dz], axial) = element(j);
            let len = crate::elastic_catenary::hypot_fast(dx, dz);
            if !(len > 0.0 && len.is_finite() && axial > 0.0 && axial.is_finite()) {
                self.clear();
                return Err(SagChainError::BadElement {
                    element: j,
                    axial_n: axial,
                    chord_m: len,
                });
            }
            let (c, s) = (dx / len, dz / len);
            let kt = axial / len;
            // (EA/l0) c cᵀ + (N/l)(I − c cᵀ), with I − c cᵀ = [s², −cs; −cs, c²] (no 1 − c²).
            let k = [
                k_axial * c * c + kt * s * s,
                (k_axial - kt) * c * s,
                k_axial * s * s + kt * c * c,
            ];
            k_max = k_max.max(k_axial).max(kt);
            self.k_in.push(k);
            self.k_out.push(kt);
            self.chord.push([c, s]);
            self.chord_m.push(len);
            self.axial_n.push(axial);
        }
        self.mass_kg = mu_kg_m * l0;
        self.l0_m = l0;
        self.k_axial = k_axial;
        self.nudge = f64::EPSILON * k_max;
        Ok(())
    }

    /// Fill the chain with `n_el` equal elements on the exact catenary `cat` (nodes at
    /// `cat.point_at_m(s_j)`, each element's chord by `cat.chord_between_m(s_j, s_j+1)`,
    /// N_j = `cat.tension_at_n` at its middle), mass per unstretched length `mu_kg_m`. No
    /// allocation; on error the chain is left empty.
    pub fn set_fem(
        &mut self,
        cat: &Catenary,
        mu_kg_m: f64,
        n_el: usize,
    ) -> Result<(), SagChainError> {
        // The elements are computed into their own scratch, taken out while `fill` writes
        // the chain (moving a Vec does not allocate).
        let mut elements = std::mem::take(&mut self.elements);
        elements.compute(cat, n_el);
        let r = self.fill(cat.ea_n, mu_kg_m, cat.l0_m, n_el, |j| {
            (elements.chord_m(j), elements.axial_n(j))
        });
        self.elements = elements;
        r
    }

    fn clear(&mut self) {
        self.k_in.clear();
        self.k_out.clear();
        self.chord.clear();
        self.chord_m.clear();
        self.axial_n.clear();
        self.mass_kg = 0.0;
        self.l0_m = 0.0;
        self.support = None;
    }

    /// Number of elements N (0 when nothing is set).
    pub fn n_el(&self) -> usize {
        self.k_in.len()
    }

    /// Largest number of elements the buffers hold.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Element mass μ l0, kg.
    pub fn element_mass_kg(&self) -> f64 {
        self.mass_kg
    }

    /// Element unstretched length l0 = L0/N, m.
    pub fn element_length_m(&self) -> f64 {
        self.l0_m
    }

    /// The string scale T̄/(m L) of the chain, 1/s² (T̄ its elements' mean tension, N; m
    /// its mass, kg; L its length along the chords, m): a taut string's eigenvalues are
    /// (jπ)² times it, so a chain's blocked eigenvalues move roughly with it from one pose
    /// to the next (a pole search's start). NaN when nothing is set.
    pub fn string_scale(&self) -> f64 {
        let n = self.axial_n.len() as f64;
        let t = self.axial_n.iter().sum::<f64>() / n;
        let l = self.chord_m.iter().sum::<f64>();
        t / (self.mass_kg * n * l)
    }

    /// Number of blocked (end held) eigenvalues: 3(N − 1) when the cable has mass, plus
    /// the hidden cable's and the junction's when the anchor is supported.
    pub fn blocked_modes(&self) -> usize {
        let own = if self.mass_kg > 0.0 {
            3 * self.n_el().saturating_sub(1)
        } else {
            0
        };
        own + self.support_modes()
    }

    /// The static end stiffness S(0): s_in (N/m, (h, up)) and s_out (N/m); the
    /// derivatives are those at λ = 0. One evaluation, [`Self::eval`] at 0 (the robot-level
    /// solver caches it per pose).
    pub fn static_eval(&self) -> SagChainEval {
        self.eval(0.0)
    }

    /// Element j (0 at the anchor).
    pub fn element(&self, j: usize) -> SagElement {
        SagElement {
            chord: self.chord[j],
            l0_m: self.l0_m,
            chord_m: self.chord_m[j],
            axial_n: self.axial_n[j],
            k_axial_n_m: self.k_axial,
            mass_kg: self.mass_kg,
            k_in: self.k_in[j],
            k_out: self.k_out[j],
        }
    }

    /// The elements from the anchor to the end (for the dense reference).
    pub fn elements(&self) -> impl ExactSizeIterator<Item = SagElement> + '_ {
        (0..self.n_el()).map(|j| self.element(j))
    }
}

/// The anchor on a hidden cable (`supported`'s docs: the junction step).
impl SagChain {
    /// Put the chain's anchor node on the hidden cable `support` (None: the anchor fixed,
    /// as [`Self::set_fem`] leaves it). Call after the chain is set: setting the chain
    /// clears its support. No allocation.
    pub fn set_support(&mut self, support: Option<SagSupport>) -> Result<(), SagChainError> {
        SagSupport::check(support.as_ref())?;
        self.support = support;
        Ok(())
    }

    /// The chain's support (None: the anchor is fixed).
    pub fn support(&self) -> Option<SagSupport> {
        self.support
    }

    /// The hidden segment's end stiffness at a real λ (its ChainEval).
    pub(super) fn hidden_at_real(support: &SagSupport, lambda: f64) -> (f64, f64, u32) {
        let e = support.hidden.eval(lambda);
        (e.s, e.ds, e.below)
    }

    /// The hidden segment's end stiffness at a complex λ (count 0).
    pub(super) fn hidden_at_complex(
        support: &SagSupport,
        lambda: Complex64,
    ) -> (Complex64, Complex64, u32) {
        let e = support.hidden.eval_at(lambda);
        (e.s, e.ds, 0)
    }

    /// Blocked eigenvalues the support adds: the hidden segment's and the junction's.
    pub(super) fn support_modes(&self) -> usize {
        match self.support {
            Some(s) => {
                s.hidden.n_poles().min(usize::MAX / 8)
                    + (self.mass_kg > 0.0 || s.hidden.m > 0.0) as usize
            }
            None => 0,
        }
    }
}
