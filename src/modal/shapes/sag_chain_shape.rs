//! One sagged FEM chain's interior solutions at one λ (`sagged`'s module docs): the three
//! solutions from the held anchor (and, on a hidden cable, the fourth from the drum), their
//! end value and end force, the junction's equation, and every node of a combination.
//!
//! **Forward solution, re-orthonormalised.** The interior equations are solved forward
//! from node 1, two nodes giving the next. Above a chain's transverse cut-off the
//! transverse solution grows like sinh(jφ) along the chain and, solved alone, every column
//! turns towards it: at the end the columns are nearly parallel and the axial one is lost
//! in their rounding (measured: the bordered system's σ_m/σ_max 4e-4 at a 6-fold cluster
//! of fast-like above its cut-off, where the null space needs ≤ 1e-3·σ_(m+1)). So after
//! each step the state of the solutions at the two newest nodes, the 6 × c matrix
//! [Y_j; Y_{j+1}] (c = 3, or 4 with the hidden cable's), is orthonormalised (modified
//! Gram-Schmidt: [Y_j; Y_{j+1}] = Q R, the columns become Q): the same span of solutions,
//! kept well conditioned. The basis changes from step to step: node j ≥ 1 is stored in the
//! basis of the step that last wrote it (b_j; the end node in b_(N−1), node 0 in b_0), and
//! with T_j = R_j⁻¹ the coefficients of one solution are c_(N−1) = a (the bordered system's
//! amplitudes, in the end's basis) and c_(j−1) = T_j c_j. The junction's equation, written
//! at node 0 and 1 in b_0, is carried to the end's basis by T_1 ⋯ T_(N−1).

use super::supported_shape::RESCALE_ABOVE;
use crate::cable::sagged::{SagChain, SagSupport};
use nalgebra::{Matrix3, Matrix3x4, Matrix4, Matrix6x4, Vector3, Vector4};

/// A column whose norm after orthogonalisation is below this fraction of its norm before
/// is dependent on the others to rounding: the step keeps its basis (the change is only
/// a conditioning aid; the span is the same without it).
const DEPENDENT: f64 = 1e-12;

/// Element j's stiffness in the cable frame, diag(K_in, k_out), N/m.
fn element_k(chain: &SagChain, j: usize) -> Matrix3<f64> {
    let e = chain.element(j);
    let [a, b, c] = e.k_in;
    Matrix3::new(a, b, 0.0, b, c, 0.0, 0.0, 0.0, e.k_out)
}

/// One cable's interior solutions at one λ, in the cable's frame (h, up, n).
#[derive(Debug, Clone, Default)]
pub(in crate::modal) struct SagChainShape {
    /// Y_j for j = 0 ..= N, each in its own basis (module docs): the solutions as columns
    /// (the fourth: the hidden cable's, zero without one).
    y: Vec<Matrix3x4<f64>>,
    /// T_j for j = 1 ..= N − 1 (index j; entry 0 unused): c_(j−1) = T_j c_j.
    back: Vec<Matrix4<f64>>,
    /// Number of solutions: 3, or 4 on a hidden cable.
    pub(super) ncol: usize,
    /// Element mass μ l0, kg.
    pub(super) mass_kg: f64,
    /// End value of each solution (cable frame, the end's basis).
    pub(super) end: Matrix3x4<f64>,
    /// End force per unit amplitude of each solution, N/m.
    pub(super) force: Matrix3x4<f64>,
    /// Row scale of the end constraint, N/m.
    pub(super) scale: f64,
    /// On a hidden cable: its nodes and the junction's equation.
    pub(super) hidden: Option<HiddenShape>,
}

/// The hidden cable of a chain: its nodes (from the drum, per unit of the fourth
/// solution's amplitude in b_0), its element mass and the junction's equation.
#[derive(Debug, Clone, Default)]
pub(super) struct HiddenShape {
    /// The hidden cable's axial nodes t_j, j = 0 ..= N_h (t_0 = 0 at the drum).
    t: Vec<f64>,
    /// The hidden cable's element mass, kg.
    mass_kg: f64,
    /// The junction's equation along d on the amplitudes (the end's basis), N/m.
    pub(super) row: Vector4<f64>,
    /// Row scale of the junction's equation, N/m.
    pub(super) scale: f64,
}

impl SagChainShape {
    /// The interior solutions of `chain` at λ (module docs).
    pub(super) fn fill(chain: &SagChain, lambda: f64) -> SagChainShape {
        let n = chain.n_el().max(1);
        let m = chain.element_mass_kg();
        let id = Matrix3::identity();
        let mut y = vec![Matrix3x4::zeros(); n + 1];
        y[1].fixed_view_mut::<3, 3>(0, 0).copy_from(&id);
        let support = chain.support();
        let hidden_t = support.map(|sp| {
            let (t, d) = hidden_nodes(&sp, lambda);
            y[0].set_column(3, &(d * t[t.len() - 1]));
            (t, d)
        });
        let ncol = if hidden_t.is_some() { 4 } else { 3 };
        // The junction's equation along d (free cable's first element, hidden cable's
        // last), in b_0, before the first change of basis.
        let row0 = hidden_t.as_ref().zip(support).map(|((t, d), sp)| {
            let k0 = element_k(chain, 0);
            let (a0, b0) = (k0 - id * (lambda * m / 3.0), -k0 - id * (lambda * m / 6.0));
            let seg = sp.hidden;
            let (ah, bh) = (seg.k - lambda * seg.m / 3.0, -seg.k - lambda * seg.m / 6.0);
            let nh = t.len() - 1;
            let on = d.transpose() * (a0 * y[0] + b0 * y[1]);
            let mut row = on.transpose();
            row[3] += ah * t[nh] + bh * t[nh - 1];
            let scale = (k0.amax() + seg.k + 0.5 * lambda * (m + seg.m)).max(f64::MIN_POSITIVE);
            (row, scale)
        });
        let mut back = vec![Matrix4::identity(); n];
        for j in 1..n {
            let (kp, kn) = (element_k(chain, j - 1), element_k(chain, j));
            let rhs = (kp + kn - id * (2.0 * lambda * m / 3.0)) * y[j]
                - (kp + id * (lambda * m / 6.0)) * y[j - 1];
            let lhs = kn + id * (lambda * m / 6.0);
            // Positive definite (K_j ⪰ 0 with T > 0, and λm ≥ 0): the solve exists.
            y[j + 1] = lhs.lu().solve(&rhs).unwrap_or_else(Matrix3x4::zeros);
            if let Some(t) = orthonormalise_state(&mut y, j, ncol) {
                back[j] = t;
            }
        }
        let kl = element_k(chain, n - 1);
        let force =
            (kl - id * (lambda * m / 3.0)) * y[n] - (kl + id * (lambda * m / 6.0)) * y[n - 1];
        let scale = (kl.amax() + 0.5 * lambda * m).max(f64::MIN_POSITIVE);
        let hidden = hidden_t
            .zip(row0)
            .zip(support)
            .map(|(((t, _), (row, sc)), sp)| {
                // The row on b_0's coefficients, carried to the end's: row · T_1 ⋯ T_(N−1).
                let mut r = row;
                for b in &back[1..] {
                    r = (r.transpose() * b).transpose();
                }
                HiddenShape {
                    t,
                    mass_kg: sp.hidden.m,
                    row: r,
                    scale: sc,
                }
            });
        SagChainShape {
            end: y[n],
            y,
            back,
            ncol,
            mass_kg: m,
            force,
            scale,
            hidden,
        }
    }

    /// The nodes j = 0 ..= N (cable frame) of the solution with amplitudes `a` (the end's
    /// basis; the fourth ignored without a hidden cable), the end node replaced by `end`,
    /// and the hidden cable's amplitude in b_0 (0 without one).
    pub(super) fn nodes(&self, a: &Vector4<f64>, end: Vector3<f64>) -> (Vec<Vector3<f64>>, f64) {
        let n = self.y.len() - 1;
        let mut u = vec![Vector3::zeros(); n + 1];
        let mut c = *a;
        if self.ncol == 3 {
            c[3] = 0.0;
        }
        // Node N and N − 1 are in b_(N−1); node j < N − 1 in b_j, reached by c ← T_(j+1) c.
        for j in (0..n).rev() {
            u[j] = self.y[j] * c;
            if j > 0 {
                c = self.back[j] * c;
            }
        }
        u[n] = end;
        let hidden = if self.ncol == 4 { c[3] } else { 0.0 };
        (u, hidden)
    }

    /// The hidden cable's nodes (axial displacement, drum to junction) for the amplitude
    /// `c` (b_0) of the fourth solution; empty without a hidden cable.
    pub(super) fn hidden_nodes(&self, c: f64) -> Vec<f64> {
        self.hidden
            .as_ref()
            .map_or_else(Vec::new, |h| h.t.iter().map(|t| t * c).collect())
    }

    /// The hidden cable's consistent mass form of amplitudes ca, cb (b_0) of this chain's
    /// and `other`'s fourth solutions (the same chain at two λ); 0 without a hidden cable.
    pub(super) fn hidden_mass_form(&self, other: &SagChainShape, ca: f64, cb: f64) -> f64 {
        let (Some(ha), Some(hb)) = (&self.hidden, &other.hidden) else {
            return 0.0;
        };
        let (ta, tb) = (&ha.t, &hb.t);
        let mut s = 0.0;
        for j in 0..ta.len().saturating_sub(1) {
            s += 2.0 * ta[j] * tb[j]
                + ta[j] * tb[j + 1]
                + ta[j + 1] * tb[j]
                + 2.0 * ta[j + 1] * tb[j + 1];
        }
        ha.mass_kg / 6.0 * s * ca * cb
    }
}

/// The hidden cable's nodes from the drum, β t_(j−1) + 2α t_j + β t_(j+1) = 0 (t_0 = 0,
/// t_1 = 1; β < 0 for λ ≥ 0), rescaled on the way, and the junction's direction d in the
/// cable frame.
fn hidden_nodes(sp: &SagSupport, lambda: f64) -> (Vec<f64>, Vector3<f64>) {
    let seg = sp.hidden;
    let nh = seg.n_el.max(1);
    let (ah, bh) = (seg.k - lambda * seg.m / 3.0, -seg.k - lambda * seg.m / 6.0);
    let mut t = vec![0.0; nh + 1];
    t[1] = 1.0;
    for j in 1..nh {
        t[j + 1] = -(bh * t[j - 1] + 2.0 * ah * t[j]) / bh;
        if t[j + 1].abs() > RESCALE_ABOVE {
            let s = 1.0 / t[j + 1].abs();
            t[..=j + 1].iter_mut().for_each(|x| *x *= s);
        }
    }
    let mx = t.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if mx > 0.0 {
        t.iter_mut().for_each(|x| *x /= mx);
    }
    (t, Vector3::new(sp.direction[0], sp.direction[1], 0.0))
}

/// Orthonormalise the state [Y_j; Y_(j+1)] (its first `ncol` columns) in place by modified
/// Gram-Schmidt; returns T = R⁻¹ (the columns became the old ones times T), or None (no
/// change) when a column is dependent on the others to rounding.
fn orthonormalise_state(y: &mut [Matrix3x4<f64>], j: usize, ncol: usize) -> Option<Matrix4<f64>> {
    let mut w = Matrix6x4::zeros();
    w.fixed_view_mut::<3, 4>(0, 0).copy_from(&y[j]);
    w.fixed_view_mut::<3, 4>(3, 0).copy_from(&y[j + 1]);
    let mut r = Matrix4::identity();
    for k in 0..ncol {
        let before = w.column(k).norm();
        for i in 0..k {
            let p = w.column(i).dot(&w.column(k));
            r[(i, k)] = p;
            let qi = w.column(i).into_owned();
            w.column_mut(k).axpy(-p, &qi, 1.0);
        }
        let after = w.column(k).norm();
        if !(after > DEPENDENT * before && after.is_finite()) {
            return None;
        }
        r[(k, k)] = after;
        w.column_mut(k).scale_mut(1.0 / after);
    }
    let t = r.try_inverse()?;
    y[j].copy_from(&w.fixed_view::<3, 4>(0, 0));
    y[j + 1].copy_from(&w.fixed_view::<3, 4>(3, 0));
    Some(t)
}
