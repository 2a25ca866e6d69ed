//! Loads on the time response besides the path's inertial load, each taken by a modal
//! response of its own on the same modes and added to the first's displacement (the
//! response is linear in its load, so the whole load's answer is the sum).
//!
//! - **The convective load** of a sagging robot's path, −M ∂²x/∂p²[ṗ, ṗ] (the nodes'
//!   acceleration quadratic in the path's velocity, the modal `quasi_static` module): the
//!   force −w of the velocity products w ([`crate::estimator::convective_input`]: six
//!   numbers) with the load shapes χ_k and the load flexibility F S
//!   ([`crate::modal::quasi_static::ConvectiveLoad`]). Off (adding nothing) where the basis
//!   has no second field (taut cables, pulleys, the dense model).
//! - **An external force on the end-effector** P (N, and N·m on a rigid body): it does work
//!   through the end-effector's displacement alone, so mode k's force is φ_kᵀ P and the
//!   static answer F P, the end-effector's own shapes and flexibility — not the inertial
//!   load's ψ_k and F_ψ, which stand for a load on every cable node (they differ by the
//!   cables' share of the quasi-static mass: nothing on massless cables, 30 % of the load
//!   on the heavy paper robot with sag).
//!
//! Each is a [`ModalResponse`] of dimension 6 (the force's six entries; φ zero beyond a
//! point mass's 3), installed with every basis of the inertial response and its state
//! carried by the same mass overlap; stepped exactly for a force linear between samples.
//! While its force has been zero since the start it stays at rest without being stepped.
//! Allocation-free after [`AddedLoad::new`].

use crate::estimator::{convective_input, EeModalBasis};
use crate::modal::response::{ModalResponse, ResponseError};
use crate::scene::Damping;
use nalgebra::{Matrix6, Vector3, Vector6};
use std::ops::AddAssign;

/// Which load an [`AddedLoad`] carries (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AddedKind {
    /// −M ∂²x/∂p²[ṗ, ṗ]: the force is [`convective_force`] of the path's velocity.
    Convective,
    /// A force (and moment) on the end-effector, N (N·m).
    EndEffectorForce,
}

/// A load's response (module docs).
#[derive(Debug, Clone)]
pub struct AddedLoad {
    kind: AddedKind,
    resp: ModalResponse,
    on: bool,
    /// At rest, the force zero since the start: nothing to step.
    quiet: bool,
}

/// The convective load's force of the path's velocity `v` (m/s): −w (m²/s²).
pub fn convective_force(v: &Vector3<f64>) -> Vector6<f64> {
    -Vector6::from(convective_input(v))
}

impl AddedLoad {
    /// Off and at rest.
    pub fn new(kind: AddedKind) -> AddedLoad {
        AddedLoad {
            kind,
            resp: ModalResponse::new(6),
            on: false,
            quiet: true,
        }
    }

    /// Whether the installed basis carries this load.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// The load's shapes and static flexibility in `basis` (None: the basis does not carry
    /// it).
    fn shapes<'a>(&self, basis: &'a EeModalBasis) -> Option<(&'a [Vector6<f64>], Matrix6<f64>)> {
        match self.kind {
            AddedKind::Convective => (basis.second_field.is_some()
                && basis.convective_load.len() == basis.lambda.len())
            .then_some((&basis.convective_load[..], basis.convective_flexibility)),
            AddedKind::EndEffectorForce => Some((&basis.phi_ee[..], basis.flexibility)),
        }
    }

    /// The load's static flexibility in `basis` (zeros where it does not carry it).
    pub fn flexibility(&self, basis: &EeModalBasis) -> Matrix6<f64> {
        self.shapes(basis).map_or(Matrix6::zeros(), |s| s.1)
    }

    /// Install `basis` (as the inertial response installs it: the state carried by the
    /// mass overlap `overlap` of the whole shapes when given, else the end-effector's), or
    /// turn off (at rest) where it does not carry this load.
    pub fn install(
        &mut self,
        basis: &EeModalBasis,
        overlap: Option<&[f64]>,
        damping: &Damping,
    ) -> Result<(), ResponseError> {
        let Some((load, flex)) = self.shapes(basis) else {
            self.resp.reset();
            self.on = false;
            return Ok(());
        };
        let (lambda, phi) = (&basis.lambda, &basis.phi_ee);
        match overlap.filter(|_| self.on) {
            Some(o) => self
                .resp
                .set_basis_projected(lambda, phi, damping, &flex, o)?,
            None => {
                let fresh = !self.on;
                self.resp
                    .set_basis(lambda, phi, damping, &flex, &basis.ee_mass)?;
                if fresh {
                    self.resp.reset(); // from rest: no motion to carry
                }
            }
        }
        self.resp.set_load_shapes(load, &flex)?;
        self.on = true;
        Ok(())
    }

    /// Advance by `h_s` under the force going linearly from `g0` to `g1`; nothing when off
    /// or while at rest under no force.
    pub fn step(&mut self, g0: &Vector6<f64>, g1: &Vector6<f64>, h_s: f64) {
        if !self.on {
            return;
        }
        if self.quiet && g0.iter().chain(g1.iter()).all(|&x| x == 0.0) {
            return;
        }
        self.quiet = false;
        self.resp.step(g0, g1, h_s);
    }

    /// The end-effector's displacement (translation, m) under the force `g` now with the
    /// static flexibility `flexibility` (interpolated between poses as the inertial
    /// response's); zero when off or quiet.
    pub fn displacement_with(&self, g: &Vector6<f64>, flexibility: &Matrix6<f64>) -> Vector3<f64> {
        if !self.on || (self.quiet && g.iter().all(|&x| x == 0.0)) {
            return Vector3::zeros();
        }
        self.resp
            .displacement_with(g, flexibility)
            .fixed_rows::<3>(0)
            .into_owned()
    }

    /// The end-effector's acceleration (translation, m/s²) under the force `g` now, from
    /// the modal state ([`ModalResponse::acceleration`]); zero when off or quiet.
    pub fn acceleration(&self, g: &Vector6<f64>) -> Vector3<f64> {
        if !self.on || self.quiet {
            return Vector3::zeros();
        }
        self.resp.acceleration(g).fixed_rows::<3>(0).into_owned()
    }
}

/// One sample's state as the loop's caller sees it: the inertial response and its force,
/// and each added load's response and force.
pub struct SampleState<'a> {
    /// The inertial load's response.
    pub inertial: &'a ModalResponse,
    /// Its force now (−M_ee [a; 0]).
    pub force: &'a Vector6<f64>,
    /// The added loads and their forces now.
    pub added: [(&'a AddedLoad, &'a Vector6<f64>); 2],
}

impl SampleState<'_> {
    /// The deviation's acceleration (translation, m/s²) from the modal states: the sum of
    /// the responses' ([`ModalResponse::acceleration`]).
    pub fn acceleration(&self) -> Vector3<f64> {
        let mut a: Vector3<f64> = self
            .inertial
            .acceleration(self.force)
            .fixed_rows::<3>(0)
            .into_owned();
        for (r, g) in &self.added {
            a += r.acceleration(g);
        }
        a
    }
}

/// The added loads of [`super::simulate`]'s loop: the convective load and an external force
/// on the end-effector, and their forces at the last sample.
#[derive(Debug, Clone)]
pub struct AddedLoads {
    loads: [AddedLoad; 2],
    now: [Vector6<f64>; 2],
}

impl Default for AddedLoads {
    fn default() -> Self {
        Self::new()
    }
}

impl AddedLoads {
    /// Both off and at rest.
    pub fn new() -> AddedLoads {
        AddedLoads {
            loads: [
                AddedLoad::new(AddedKind::Convective),
                AddedLoad::new(AddedKind::EndEffectorForce),
            ],
            now: [Vector6::zeros(); 2],
        }
    }

    /// The forces at a sample: the convective force of the path's velocity `v` (m/s) and
    /// the external force `external` (N, N·m).
    pub fn forces(v: &Vector3<f64>, external: &Vector6<f64>) -> [Vector6<f64>; 2] {
        [convective_force(v), *external]
    }

    /// Install `basis` in each ([`AddedLoad::install`]).
    pub fn install(
        &mut self,
        basis: &EeModalBasis,
        overlap: Option<&[f64]>,
        damping: &Damping,
    ) -> Result<(), ResponseError> {
        for l in &mut self.loads {
            l.install(basis, overlap, damping)?;
        }
        Ok(())
    }

    /// The forces of the first sample (before any step).
    pub fn start(&mut self, forces: [Vector6<f64>; 2]) {
        self.now = forces;
    }

    /// Advance by `h_s` to the sample of `forces` (each linear from the last sample's).
    pub fn step(&mut self, forces: [Vector6<f64>; 2], h_s: f64) {
        for ((l, now), f) in self.loads.iter_mut().zip(&mut self.now).zip(forces) {
            l.step(now, &f, h_s);
            *now = f;
        }
    }

    /// Their displacement of the end-effector now (translation in the first 3 entries, m),
    /// each static flexibility interpolated from `held`'s to `next`'s by `w` (0 ..= 1).
    pub fn displacement(&self, held: &EeModalBasis, next: &EeModalBasis, w: f64) -> Vector6<f64> {
        let mut u = Vector6::zeros();
        for (l, g) in self.loads.iter().zip(&self.now) {
            let flex = l.flexibility(held) * (1.0 - w) + l.flexibility(next) * w;
            u.fixed_rows_mut::<3>(0)
                .add_assign(&l.displacement_with(g, &flex));
        }
        u
    }

    /// The sample's state with the inertial response `inertial` under its force `force`.
    pub fn state<'a>(
        &'a self,
        inertial: &'a ModalResponse,
        force: &'a Vector6<f64>,
    ) -> SampleState<'a> {
        SampleState {
            inertial,
            force,
            added: [
                (&self.loads[0], &self.now[0]),
                (&self.loads[1], &self.now[1]),
            ],
        }
    }
}
