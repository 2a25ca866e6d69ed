//! The taut chains' bordered system ([`TautSystem`], behind
//! [`ModalSolver::mode_shapes`](crate::modal::ModalSolver::mode_shapes)): one scalar chain
//! copy per direction of each chain, its amplitude C_k one unknown (the module docs); the
//! pipeline (`pipeline`) takes its null space, normalises and repairs clusters.

use super::bordered::{element_mass_form, Bordered, Nodes};
use super::chain_shape::ChainShape;
use super::{ModeShapes, ShapeError, ShapeParams};
use crate::cable::{CableModel, ChainKind};
use crate::eig3::eig3_jacobi;
use crate::kinematics::attach_map;
use crate::modal::engine::Condensed;
use crate::modal::TautChains;
use nalgebra::{DMatrix, DVector, Matrix3x6, Matrix6, Vector3, Vector6};

/// A projector eigenvalue above this is in its range (they are 0 or 1 to rounding).
const PROJ_RANGE_MIN: f64 = 0.5;

/// One chain copy: a direction of one chain of one cable.
#[derive(Debug, Clone)]
pub(super) struct ChainCopy {
    /// The chain's index in [`Layout::kinds`].
    pub(super) chain: usize,
    /// Unit direction of the copy (world frame).
    dir: Vector3<f64>,
    /// End direction on the end-effector's coordinates, G_iᵀ dir.
    pub(super) b: Vector6<f64>,
}

/// How the models' chains attach, independent of λ.
#[derive(Debug, Clone)]
pub(super) struct Layout {
    /// Each active chain's kind.
    pub(super) kinds: Vec<ChainKind>,
    /// Every chain copy.
    pub(super) copies: Vec<ChainCopy>,
    /// Per cable: its copies' indices, its attachment map and whether it is continuous.
    cable_copies: Vec<Vec<usize>>,
    attach: Vec<Matrix3x6<f64>>,
    fractions: Vec<Vec<f64>>,
    /// Per cable: its discrete hidden cable's element mass, kg (0 without one).
    hidden_mass_kg: Vec<f64>,
}

impl Layout {
    fn new(
        models: &[CableModel],
        arms_m: Option<&[nalgebra::Vector3<f64>]>,
        samples: usize,
    ) -> Layout {
        let mut l = Layout {
            kinds: Vec::new(),
            copies: Vec::new(),
            cable_copies: Vec::new(),
            attach: Vec::new(),
            fractions: Vec::new(),
            hidden_mass_kg: Vec::new(),
        };
        for (i, m) in models.iter().enumerate() {
            let g = match arms_m {
                Some(arms) => attach_map(&arms[i]),
                None => attach_map(&Vector3::zeros()),
            };
            let mut mine = Vec::new();
            let mut continuous = false;
            let mut hidden_kg = 0.0;
            for c in &m.chains[..m.n_chains] {
                if matches!(c.kind, ChainKind::Discrete { k, m, .. } if k == 0.0 && m == 0.0) {
                    continue; // no stiffness, no mass: loads nothing (as `load` skips it)
                }
                continuous |= matches!(c.kind, ChainKind::Continuous { .. })
                    || matches!(c.kind, ChainKind::Supported { free, .. } if free.n_el == 0);
                if let ChainKind::Supported { hidden, .. } = c.kind {
                    if hidden.n_el > 0 {
                        hidden_kg = hidden.m;
                    }
                }
                let e = eig3_jacobi(&c.proj);
                for r in 0..3 {
                    if e.values[r] > PROJ_RANGE_MIN {
                        let dir = e.vectors[r];
                        mine.push(l.copies.len());
                        l.copies.push(ChainCopy {
                            chain: l.kinds.len(),
                            dir,
                            b: g.transpose() * dir,
                        });
                    }
                }
                l.kinds.push(c.kind);
            }
            let n = if continuous {
                samples - 1
            } else {
                m.n_el.max(1)
            };
            l.fractions
                .push((0..=n).map(|j| j as f64 / n as f64).collect());
            l.cable_copies.push(mine);
            l.attach.push(g);
            l.hidden_mass_kg.push(hidden_kg);
        }
        l
    }
}

impl Layout {
    /// Each cable's element mass between its node list's nodes, kg (its first chain's: all
    /// chains of a cable share the element mass; 0 without chains).
    fn element_mass_kg(&self) -> Vec<f64> {
        self.cable_copies
            .iter()
            .zip(&self.fractions)
            .map(
                |(copies, fr)| match copies.first().map(|&q| self.kinds[self.copies[q].chain]) {
                    Some(ChainKind::Discrete { m, .. }) => m,
                    Some(ChainKind::Continuous { m_total, .. }) => {
                        m_total / (fr.len().saturating_sub(1)).max(1) as f64
                    }
                    // A supported chain's free cable: its element mass, or its whole mass
                    // over the sample intervals (continuous).
                    Some(ChainKind::Supported { free, .. }) if free.n_el > 0 => free.m,
                    Some(ChainKind::Supported { free, .. }) => {
                        free.m / (fr.len().saturating_sub(1)).max(1) as f64
                    }
                    _ => 0.0,
                },
            )
            .collect()
    }
}

/// The taut chains' bordered system (module docs): the loaded chains and their layout.
pub(in crate::modal) struct TautSystem<'a> {
    pub(super) chains: &'a mut TautChains,
    pub(super) layout: Layout,
    /// Every chain is a discrete FEM chain (the mass form of two chain solutions at
    /// different λ is then the node form, exact).
    discrete: bool,
}

/// A null vector of the taut system: the vector and each chain copy's end displacement
/// e = b_kᵀφ.
pub(in crate::modal) struct TautVector {
    col: DVector<f64>,
    ends: Vec<f64>,
}

impl<'a> TautSystem<'a> {
    /// The bordered system of `chains`, loaded with the cable models `models` (arms `arms_m`
    /// of a rigid end-effector, world frame, m; ignored for a point mass), and the empty
    /// shapes with its node lists (continuous cables at
    /// [`ShapeParams::continuous_samples`] points); for
    /// [`ModalSolver::mode_shapes`](crate::modal::ModalSolver::mode_shapes).
    pub(in crate::modal) fn new(
        chains: &'a mut TautChains,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
        params: &ShapeParams,
    ) -> Result<(TautSystem<'a>, ModeShapes), ShapeError> {
        params.check()?;
        let dim = chains.p.dim;
        if dim == 6 && arms_m.len() < models.len() {
            return Err(ShapeError::MissingArms {
                given: arms_m.len(),
                cables: models.len(),
            });
        }
        if models.iter().any(|m| {
            m.chains[..m.n_chains].iter().any(|c| {
                matches!(c.kind, ChainKind::Supported { free, hidden }
                    if (free.n_el == 0) != (hidden.n_el == 0))
            })
        }) {
            return Err(ShapeError::HiddenCable);
        }
        let arms = (dim == 6).then_some(arms_m);
        let layout = Layout::new(models, arms, params.continuous_samples);
        if layout.kinds.len() != chains.p.n_chains {
            return Err(ShapeError::NotLoaded {
                loaded: chains.p.n_chains,
                given: layout.kinds.len(),
            });
        }
        let out = ModeShapes {
            dim,
            fractions: layout.fractions.clone(),
            modes: Vec::new(),
            element_mass_kg: layout.element_mass_kg(),
            hidden_element_mass_kg: layout.hidden_mass_kg.clone(),
        };
        let discrete = layout
            .kinds
            .iter()
            .all(|k| matches!(k, ChainKind::Discrete { .. }));
        Ok((
            TautSystem {
                chains,
                layout,
                discrete,
            },
            out,
        ))
    }
}

impl Bordered for TautSystem<'_> {
    type At = Vec<ChainShape>;
    type Vector = TautVector;

    fn dim(&self) -> usize {
        self.chains.p.dim
    }

    fn ee_mass(&self) -> Matrix6<f64> {
        self.chains.p.m6
    }

    fn at(&mut self, lambda: f64) -> Vec<ChainShape> {
        let mut shapes = vec![ChainShape::default(); self.layout.kinds.len()];
        for (sh, kind) in shapes.iter_mut().zip(&self.layout.kinds) {
            sh.fill(kind, lambda);
        }
        shapes
    }

    fn matrix(&self, shapes: &Vec<ChainShape>, lambda: f64) -> DMatrix<f64> {
        let p = &self.chains.p;
        let d = p.dim;
        let n = d + self.layout.copies.len();
        let mut a = DMatrix::<f64>::zeros(n, n);
        for r in 0..d {
            for c in 0..d {
                a[(r, c)] = p.k6[(r, c)] - lambda * p.m6[(r, c)];
            }
        }
        for (q, cp) in self.layout.copies.iter().enumerate() {
            let sh = &shapes[cp.chain];
            for r in 0..d {
                a[(r, d + q)] = sh.f * cp.b[r];
                a[(d + q, r)] = sh.scale * cp.b[r];
            }
            a[(d + q, d + q)] = -sh.scale * sh.g;
        }
        a
    }

    fn vector(&self, _: &Vec<ChainShape>, col: &DVector<f64>) -> TautVector {
        let d = self.dim();
        let ends = self
            .layout
            .copies
            .iter()
            .map(|cp| (0..d).map(|r| cp.b[r] * col[r]).sum())
            .collect();
        TautVector {
            col: col.clone(),
            ends,
        }
    }

    fn cable_mass(
        &self,
        at_a: &Vec<ChainShape>,
        a: &TautVector,
        at_b: &Vec<ChainShape>,
        b: &TautVector,
        same: bool,
    ) -> Option<f64> {
        if !same {
            // Two λ: the node form of discrete chains (their consistent mass exactly).
            if !self.discrete {
                return None;
            }
            let (na, nb) = (self.nodes(at_a, a).0, self.nodes(at_b, b).0);
            let mass = self.layout.element_mass_kg();
            return Some(
                na.iter()
                    .zip(&nb)
                    .zip(&mass)
                    .map(|((u, v), &m)| element_mass_form(m, u, v))
                    .sum(),
            );
        }
        let d = self.dim();
        let mut cab = 0.0;
        for (q, cp) in self.layout.copies.iter().enumerate() {
            let sh = &at_a[cp.chain];
            let (ca, cb) = (a.col[d + q], b.col[d + q]);
            let (ea, eb) = (a.ends[q], b.ends[q]);
            cab += ca * cb * sh.m_ii + (ca * eb + ea * cb) * sh.m_ie + ea * eb * sh.m_ee;
        }
        Some(cab)
    }

    fn nodes(&self, shapes: &Vec<ChainShape>, v: &TautVector) -> Nodes {
        self.col_nodes(shapes, &v.col)
    }

    fn count(&mut self, lambda: f64) -> u32 {
        self.chains.count(lambda).0
    }
}

impl TautSystem<'_> {
    /// Every cable's node displacements of a bordered vector `col` (φ, C_1 … C_n): C_k w
    /// inside, G_i φ at the end; and each hidden cable's, C_k times the supported chain's
    /// hidden nodes (empty without one).
    pub(super) fn col_nodes(&self, shapes: &[ChainShape], col: &DVector<f64>) -> Nodes {
        let layout = &self.layout;
        let dim = self.dim();
        let mut phi = Vector6::zeros();
        for r in 0..dim {
            phi[r] = col[r];
        }
        let hidden = layout
            .cable_copies
            .iter()
            .map(|copies| {
                copies
                    .iter()
                    .find(|&&q| !shapes[layout.copies[q].chain].hidden_w.is_empty())
                    .map(|&q| {
                        let amp = col[dim + q];
                        let sh = &shapes[layout.copies[q].chain];
                        sh.hidden_w.iter().map(|w| amp * w).collect()
                    })
                    .unwrap_or_default()
            })
            .collect();
        let cables = layout
            .cable_copies
            .iter()
            .enumerate()
            .map(|(i, copies)| {
                let fr = &layout.fractions[i];
                let last = fr.len() - 1;
                let mut u = vec![Vector3::zeros(); fr.len()];
                for &q in copies {
                    let cp = &layout.copies[q];
                    let sh = &shapes[cp.chain];
                    let amp = col[dim + q];
                    // Node 0 moves only on a hidden cable (the junction at its pulley).
                    for (j, uj) in u.iter_mut().enumerate().take(last) {
                        let w = if sh.w.is_empty() {
                            sh.at(fr[j])
                        } else {
                            sh.w[j]
                        };
                        *uj += cp.dir * (amp * w);
                    }
                }
                u[last] = layout.attach[i] * phi;
                u
            })
            .collect();
        (cables, hidden)
    }
}
