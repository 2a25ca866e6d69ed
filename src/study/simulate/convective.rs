//! The convective load of a sagging robot's path on the time response: −M ∂²x/∂p²[ṗ, ṗ]
//! (the nodes' acceleration quadratic in the path's velocity, the modal `quasi_static`
//! module), taken by a second modal response on the same modes and added to the first's
//! displacement.
//!
//! The response is linear in its load, so the whole load's answer is the sum of the
//! inertial load's (the end-effector force −M_ee a with the load shapes ψ_k) and the
//! convective load's: the same modes (λ, φ, damping), stepped exactly for a force linear
//! between samples, the force −w of the velocity products w
//! ([`crate::estimator::convective_input`]: six numbers, hence a response of dimension 6
//! whose φ are the end-effector's, zeros beyond a point mass's 3) with the load shapes χ_k
//! and the load flexibility F S ([`crate::modal::quasi_static::ConvectiveLoad`]). Across a
//! basis update its state is carried by the same mass overlap as the first's. Where the
//! basis has no second field (taut cables, pulleys, the dense model) it is off and adds
//! nothing. Allocation-free after [`Convective::new`].

use crate::estimator::{convective_input, EeModalBasis};
use crate::modal::response::{ModalResponse, ResponseError};
use crate::scene::Damping;
use nalgebra::{Matrix6, Vector3, Vector6};

/// The convective load's response (module docs).
#[derive(Debug, Clone)]
pub struct Convective {
    resp: ModalResponse,
    on: bool,
}

impl Default for Convective {
    fn default() -> Self {
        Self::new()
    }
}

/// The response's force of the path's velocity `v` (m/s): −w (m²/s²).
pub fn convective_force(v: &Vector3<f64>) -> Vector6<f64> {
    -Vector6::from(convective_input(v))
}

impl Convective {
    /// Off and at rest.
    pub fn new() -> Convective {
        Convective {
            resp: ModalResponse::new(6),
            on: false,
        }
    }

    /// Whether the installed basis carries the convective load.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// Install `basis` (as the inertial response installs it: the state carried by the
    /// mass overlap `overlap` of the whole shapes when given, else the end-effector's),
    /// or turn off (at rest) where it has no second field.
    pub fn install(
        &mut self,
        basis: &EeModalBasis,
        overlap: Option<&[f64]>,
        damping: &Damping,
    ) -> Result<(), ResponseError> {
        if basis.second_field.is_none() || basis.convective_load.len() != basis.lambda.len() {
            self.resp.reset();
            self.on = false;
            return Ok(());
        }
        let flex = basis.convective_flexibility;
        match overlap.filter(|_| self.on) {
            Some(o) => {
                self.resp
                    .set_basis_projected(&basis.lambda, &basis.phi_ee, damping, &flex, o)?
            }
            None => {
                self.resp.set_basis(
                    &basis.lambda,
                    &basis.phi_ee,
                    damping,
                    &flex,
                    &basis.ee_mass,
                )?;
                // From rest: no motion to carry.
                self.resp.reset();
            }
        }
        self.resp.set_load_shapes(&basis.convective_load, &flex)?;
        self.on = true;
        Ok(())
    }

    /// Advance by `h_s` under the force going linearly from `g0` to `g1`
    /// ([`convective_force`]); nothing when off.
    pub fn step(&mut self, g0: &Vector6<f64>, g1: &Vector6<f64>, h_s: f64) {
        if self.on {
            self.resp.step(g0, g1, h_s);
        }
    }

    /// The end-effector's displacement (translation, m) under the force `g` now with the
    /// load flexibility `flexibility` (interpolated between poses as the inertial
    /// response's); zero when off.
    pub fn displacement_with(&self, g: &Vector6<f64>, flexibility: &Matrix6<f64>) -> Vector3<f64> {
        if !self.on {
            return Vector3::zeros();
        }
        self.resp
            .displacement_with(g, flexibility)
            .fixed_rows::<3>(0)
            .into_owned()
    }
}
