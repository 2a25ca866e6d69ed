//! A pose's modal basis by Rayleigh–Ritz from a nearby pose's shapes
//! ([`crate::modal::ritz`]): the cheap update of a time response along a path, where the
//! structured shapes ([`Estimator::ee_modal_basis`]) cost a root search and a bordered
//! solve per mode.
//!
//! The start block is the previous basis's whole shapes (K modes and the guard modes above
//! them) in the DOF order of the assembly in cable frames
//! ([`crate::modal::assemble_in_cable_frames`]: the end-effector, then each cable's interior
//! nodes in the frame of its element block's eigenvectors, a direction at a time: every
//! direction a scalar chain); the Ritz vectors are rotated back node by node and go into
//! shapes on the same nodes (the anchor still, the end node the end-effector's attachment
//! G_i φ_ee), with the element masses of the new pose. The load of the whole robot's
//! quasi-static inertia is formed as the structured basis forms it, from the new pose's
//! influence field. Taut FEM chains without a hidden cable only; elsewhere (sagging
//! cables, pulleys' hidden cables, continuous cables) there is no update and the caller
//! takes the structured shapes.

use super::dof_shapes::DofLayout;
use super::{BasisError, EeModalBasis, Estimator, Status};
use crate::cable::ChainKind;
use crate::modal::quasi_static::QuasiStaticLoad;
use crate::modal::ritz::{subspace_iteration, Pencil, RitzParams, RitzSchedule};
use crate::modal::{CableFrames, ModeShapes, ShapeParams};
use nalgebra::{DMatrix, Vector3};

/// Largest model the update is made for, DOF: its sweeps cost O(n q) and its blocks take
/// n × q values each (q the kept and guard modes, a few blocks); beyond it the structured
/// shapes, whose cost does not grow with the elements.
pub const MAX_RITZ_DOF: usize = 1500;

/// Most sweeps of one update (each costs one block solve; a checked sweep a small
/// eigen-solve too; [`crate::modal::ritz::RitzSchedule`] says which are checked). Measured
/// on the paper robot's circle (K = 39, K/3 = 13 guard modes, 863 bases): the slowest
/// updates meet the bound at the 14th-15th sweep, where the contraction a sweep makes is
/// slow while a mode crosses the top of the block; at most 16 leave one of the 779 updates
/// to the structured shapes.
pub const RITZ_SWEEPS: usize = 16;

/// What [`Estimator::ee_modal_basis_ritz`] made.
#[derive(Debug, Clone, PartialEq)]
pub struct RitzBasis {
    /// The basis of the first K modes (a cluster cut completed), as
    /// [`Estimator::ee_modal_basis`] gives it.
    pub basis: EeModalBasis,
    /// Every Ritz vector (the kept modes and the guards above them): the next update's
    /// start block.
    pub space: ModeShapes,
    /// The largest relative residual ρ of the kept modes ([`crate::modal::ritz`]).
    pub residual: f64,
    /// Sweeps made.
    pub sweeps: usize,
}

impl Estimator {
    /// Whether this model has the update of the module docs (taut FEM chains without a
    /// hidden cable, assembled within `MAX_RITZ_DOF` DOF).
    pub fn ritz_update_applies(&mut self) -> bool {
        let (_, dim, _) = self.ee_mass_flexibility();
        self.cycle
            .taut_shapes_input()
            .is_some_and(|(_, models, _)| {
                models.iter().all(|m| {
                    m.hidden.is_none()
                        && m.chains[..m.n_chains]
                            .iter()
                            .all(|c| matches!(c.kind, ChainKind::Discrete { .. }))
                }) && crate::modal::assembled_dof(models, dim).is_some_and(|n| n <= MAX_RITZ_DOF)
            })
    }

    /// The first `k` modes (a cluster cut completed) at the last cycle's pose by subspace
    /// iteration from `start` (module docs), accepted when every kept mode's relative
    /// residual is within `max_residual` after at most [`RITZ_SWEEPS`] sweeps. `Ok(None)`
    /// where the model has no such update (module docs), `start` is not this model's shapes
    /// or holds no more than K modes, or the residual is not met. `schedule` says at which
    /// sweep the iteration is first checked and learns from this update (the state a
    /// sequence of updates carries, [`RitzSchedule`]).
    pub fn ee_modal_basis_ritz(
        &mut self,
        start: &ModeShapes,
        k: usize,
        max_residual: f64,
        schedule: &mut RitzSchedule,
    ) -> Result<Option<RitzBasis>, BasisError> {
        if self.estimate.status != Status::Ok || start.modes.len() <= k {
            return Ok(None);
        }
        let (ee_mass, dim, flexibility) = self.ee_mass_flexibility();
        if !self.ritz_update_applies() {
            return Ok(None);
        }
        let Some((_, models, geometry)) = self.cycle.taut_shapes_input() else {
            return Ok(None);
        };
        let arms = geometry.arm_m.clone();
        let nodes: Vec<usize> = models.iter().map(|m| m.n_el + 1).collect();
        let element_mass_kg: Vec<f64> = models.iter().map(|m| m.element_mass_kg).collect();
        let same_nodes = start.dim == dim
            && start.fractions.len() == nodes.len()
            && start
                .fractions
                .iter()
                .zip(&nodes)
                .all(|(f, &n)| f.len() == n);
        if !same_nodes {
            return Ok(None);
        }
        // K and M with each cable's nodes in its own frame: every direction a scalar chain,
        // so that the factors' rows hold one entry beside the diagonal (module docs).
        let Some(Ok(assembly)) = self.cycle.assemble_in_cable_frames(&self.scene) else {
            return Ok(None);
        };
        let CableFrames { entries, frames } = assembly;
        let n = entries.dof;
        if n != dim + nodes.iter().map(|&c| 3 * (c - 2)).sum::<usize>() {
            return Ok(None);
        }
        // The start block in the assembly's DOF order, each node in its cable's frame.
        let q = start.modes.len();
        let mut x = DMatrix::zeros(n, q);
        for (c, mode) in start.modes.iter().enumerate() {
            for r in 0..dim {
                x[(r, c)] = mode.ee[r];
            }
            let mut base = dim;
            for ((cable, &count), frame) in mode.cables.iter().zip(&nodes).zip(&frames) {
                for j in 1..count - 1 {
                    let local = frame.tr_mul(&cable[j]);
                    for a in 0..3 {
                        x[(CableFrames::dof(base, count - 1, j, a), c)] = local[a];
                    }
                }
                base += 3 * (count - 2);
            }
        }
        // The kept modes: K, completed to the start's cluster end.
        let mut kept = k.max(1);
        while kept < q && start.modes[kept].cluster_start < kept {
            kept += 1;
        }
        if kept >= q {
            return Ok(None);
        }
        let params = RitzParams {
            max_residual,
            max_sweeps: RITZ_SWEEPS,
            min_sweeps: schedule.first_check(),
            rate: schedule.rate(),
        };
        let Ok(pencil) = Pencil::from_entries(&entries, dim) else {
            return Ok(None);
        };
        let Ok(mut ritz) = subspace_iteration(&pencil, x, kept, &params) else {
            return Ok(None);
        };
        // The Ritz vectors back in the world frame and the node-by-node DOF order, a column
        // and a cable at a time.
        let mut world = Vec::new();
        for mut col in ritz.vectors.column_iter_mut() {
            let mut base = dim;
            for (&count, frame) in nodes.iter().zip(&frames) {
                world.clear();
                for j in 1..count - 1 {
                    let at = |a: usize| col[CableFrames::dof(base, count - 1, j, a)];
                    world.extend((frame * Vector3::new(at(0), at(1), at(2))).iter());
                }
                for (i, w) in world.iter().enumerate() {
                    col[base + i] = *w;
                }
                base += 3 * (count - 2);
            }
        }
        schedule.learn(&ritz, max_residual);
        let residual = ritz.max_residual();
        if !(residual <= max_residual) {
            return Ok(None);
        }
        let layout = DofLayout {
            dim,
            fractions: &start.fractions,
            element_mass_kg: &element_mass_kg,
            arm_m: &arms,
        };
        let space = layout.shapes(
            &ritz.lambda[..q],
            &ritz.vectors,
            &ritz.residual,
            &ee_mass,
            0.0,
        );
        // A cluster the Ritz values join across the start's cut: no update.
        if space.modes[kept].cluster_start < kept {
            return Ok(None);
        }
        // The kept modes only (the guards' shapes are not copied).
        let shapes = ModeShapes {
            dim: space.dim,
            fractions: space.fractions.clone(),
            modes: space.modes[..kept].to_vec(),
            element_mass_kg: space.element_mass_kg.clone(),
            hidden_element_mass_kg: space.hidden_element_mass_kg.clone(),
        };
        let field = self
            .cycle
            .taut_shapes_input()
            .map(|(solver, models, geometry)| {
                solver.influence_field(models, &geometry.arm_m, &ShapeParams::default())
            });
        let load = match field {
            Some(Ok(field)) => QuasiStaticLoad::from_shapes(&shapes, &field, &ee_mass)
                .map(|load| (load, field))
                .ok_or(BasisError::QuasiStatic(super::modes::NODES_DIFFER))?,
            Some(Err(e)) => return Err(BasisError::Shapes(e)),
            None => return Ok(None),
        };
        // Taut chains only (the cheap update's scope): no convective load, which is a
        // sagging robot's.
        let basis = EeModalBasis::structured(dim, shapes, Some(load), None, flexibility, ee_mass)?;
        Ok(Some(RitzBasis {
            basis,
            space,
            residual,
            sweeps: ritz.sweeps,
        }))
    }
}
