//! The inertial load of the quasi-static motion on the whole robot: the end-effector's mass
//! and the cables' own, carried along by the end-effector.
//!
//! **Model.** While the robot follows a path quasi-statically, every node of the model sits
//! at the static equilibrium of the end-effector's pose: with the end-effector's DOFs e
//! (3, or 6 for a rigid body) and the cables' interior nodes i, the nodes move by
//! x_qs = r p(t), r = [I; −K_ii⁻¹ K_ie] the static condensation's influence field
//! ([`crate::modal::ModalSolver::influence_field`], sagged:
//! [`crate::modal::SagModalSolver::influence_field`]). The deviation u from it obeys
//!
//! ```text
//!     M ü + C u̇ + K u = −M r a,    a = p̈ (the path's acceleration, and α for a rigid body)
//! ```
//!
//! M the whole robot's mass (end-effector and cables). With the mass-normalised modes φ_k
//! the modal forces are −L_kᵀ a with the participation factors
//!
//! ```text
//!     L_k = φ_kᵀ M r   (dim numbers per mode, kg^½; [`crate::modal::ModeShapes::mass_overlap`]),
//! ```
//!
//! and the load's static answer at the end-effector is F rᵀ(−M r a) = −F M_qs a, F the
//! end-effector's static flexibility and M_qs = rᵀ M r the robot's quasi-static mass
//! (dim × dim, kg: the end-effector's plus about a third of each taut cable's mass, the
//! share ∫ s² dm of a linear field). The end-effector's own load −M_ee a is the part of
//! this with the cables' mass left out (M_ee in place of M on the cables' nodes).
//!
//! **As an end-effector load.** A response written for the force f = −M_ee a on the
//! end-effector ([`crate::modal::response::ModalResponse`]) takes this load exactly when
//! each mode's force is taken with the load shape ψ_k = M_ee⁻¹ L_k (ψ_kᵀ f = −L_kᵀ a) and the
//! static answer with the load flexibility F_ψ = F M_qs M_ee⁻¹ (F_ψ f = −F M_qs a), while
//! the displacement stays Σ φ_k q_k: the load shapes and flexibility of
//! [`QuasiStaticLoad::load_shapes`] and [`QuasiStaticLoad::load_flexibility`]. Without cable
//! mass L_k = M_ee φ_k, so ψ_k = φ_k and F_ψ = F: today's end-effector load. Only the
//! dim × dim blocks are used (a point mass: translations).
//!
//! **Sagging cables: the path's field.** The field r above holds every cable at its
//! unstretched length, the linear model's own static condensation. Along a path the
//! winches change the lengths with the pose, and the nodes (at fixed fractions of the
//! length) follow the sagged equilibrium of each pose's tension distribution instead: the
//! path's field r_p = ∂x/∂p (`estimator::path_field`). On taut cables both are the linear
//! interpolation along the chord; on a slack sagging cable they are not: at fixed length a
//! chord change changes the sag by many times the end-effector's motion (`suspended-8`
//! with sag: the fixed-length field's M_qs = 545.6 kg against an end-effector of 50 kg,
//! and a response 11× the end-effector-only one), far more than the path's catenaries
//! move. With the path's field the load is −M r_p a and
//!
//! ```text
//!     L_k = φ_kᵀ M r_p,   M_qs = r_pᵀ M r_p,   static answer F r_sᵀ(−M r_p a) = −F M_s a,
//!     M_s = r_sᵀ M r_p,
//! ```
//!
//! r_s the fixed-length field: the end-effector rows of K⁻¹ are F r_sᵀ, whatever the load.
//! So the load flexibility is F M_s M_ee⁻¹ ([`QuasiStaticLoad::from_path_field`]); on taut
//! cables r_p = r_s and M_s = M_qs. Sagging robots whose cables run over pulleys are not
//! covered by the path's field and take the end-effector's load alone
//! ([`QuasiStaticLoad::end_effector_only`]).
//!
//! **The convective load.** Along a path p(t) the nodes x(p(t)) accelerate by
//! r_p p̈ + ∂²x/∂p²[ṗ, ṗ]; the second term loads the robot by −M ∂²x/∂p²[ṗ, ṗ], a load
//! quadratic in the path's velocity that no end-effector force carries. With the six
//! second-derivative fields C_i = ∂²x/∂p_d∂p_e (pairs xx, yy, zz, xy, xz, yz; the
//! end-effector's entries zero) and the velocity's products w = [ṗ_x², ṗ_y², ṗ_z², 2ṗ_xṗ_y,
//! 2ṗ_xṗ_z, 2ṗ_yṗ_z] (so ∂²x/∂p²[ṗ, ṗ] = Σ_i C_i w_i), mode k's force is −χ_kᵀ w and the
//! static answer F r_sᵀ(−M C w) = −F S w with
//!
//! ```text
//!     χ_k,i = φ_kᵀ M C_i   (kg^½/m),   S_di = r_s,dᵀ M C_i   (kg/m)
//! ```
//!
//! ([`ConvectiveLoad`]): a second load on the same modes, taken by a response whose force
//! is −w with load shapes χ_k and load flexibility F S. On taut cables the field is linear
//! in the pose along each chord to first order and the term is not formed.

use super::ModeShapes;
use nalgebra::{DMatrix, Matrix6, Vector6};

/// The participation factors and quasi-static mass of one pose's modes (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct QuasiStaticLoad {
    /// 3 (point mass) or 6 (rigid body).
    pub dim: usize,
    /// L_k = φ_kᵀ M r of each mode (its first `dim` entries; kg^½, kg^½·m for rotations).
    pub participation: Vec<Vector6<f64>>,
    /// M_qs = rᵀ M r, kg (kg·m, kg·m² in a rigid body's rotational blocks; zeros beyond
    /// `dim`).
    pub mass_kg: Matrix6<f64>,
    /// M_s = r_sᵀ M r of the static answer, r_s the fixed-length field (module docs; kg,
    /// as `mass_kg`): `mass_kg` itself unless the field is a sagging robot's path field.
    pub static_mass_kg: Matrix6<f64>,
}

/// The dim × dim products `a`ᵀ M `b` of two fields (the same node lists) by the consistent
/// mass, as a 6 × 6 (zeros beyond `dim`); `symmetric` averages it with its transpose
/// against the sums' rounding. None when the node lists differ.
fn field_product(
    a: &ModeShapes,
    b: &ModeShapes,
    ee_mass: &Matrix6<f64>,
    symmetric: bool,
) -> Option<Matrix6<f64>> {
    let dim = a.modes.len();
    let p = a.mass_overlap(b, ee_mass)?;
    let mut out = Matrix6::zeros();
    for r in 0..dim {
        for c in 0..dim {
            out[(r, c)] = if symmetric {
                0.5 * (p[r * dim + c] + p[c * dim + r])
            } else {
                p[r * dim + c]
            };
        }
    }
    Some(out)
}

impl QuasiStaticLoad {
    /// From the structured shapes of a pose and its influence field (the same node lists),
    /// the end-effector's mass `ee_mass` (kg, kg·m²): both products by the consistent mass
    /// of [`ModeShapes::mass_overlap`]. None when the node lists differ. The hidden cables'
    /// own mass (behind their pulleys) is not in the shapes' node lists and is left out.
    pub fn from_shapes(
        shapes: &ModeShapes,
        field: &ModeShapes,
        ee_mass: &Matrix6<f64>,
    ) -> Option<QuasiStaticLoad> {
        Self::from_path_field(shapes, field, field, ee_mass)
    }

    /// As [`Self::from_shapes`] with the path's field `path` of a sagging robot and the
    /// fixed-length field `fixed` (module docs): L_k = φ_kᵀ M r_p, M_qs = r_pᵀ M r_p and
    /// M_s = r_sᵀ M r_p. None when the node lists differ.
    pub fn from_path_field(
        shapes: &ModeShapes,
        path: &ModeShapes,
        fixed: &ModeShapes,
        ee_mass: &Matrix6<f64>,
    ) -> Option<QuasiStaticLoad> {
        let dim = path.modes.len();
        if dim != shapes.dim || fixed.modes.len() != dim {
            return None;
        }
        let l = shapes.mass_overlap(path, ee_mass)?;
        let participation = (0..shapes.modes.len())
            .map(|k| {
                let mut v = Vector6::zeros();
                for d in 0..dim {
                    v[d] = l[k * dim + d];
                }
                v
            })
            .collect();
        let mass_kg = field_product(path, path, ee_mass, true)?;
        // The same products when the fields are one (taut cables): bit for bit M_qs.
        let static_mass_kg = if std::ptr::eq(path, fixed) {
            mass_kg
        } else {
            field_product(fixed, path, ee_mass, false)?
        };
        Some(QuasiStaticLoad {
            dim,
            participation,
            mass_kg,
            static_mass_kg,
        })
    }

    /// The end-effector's load alone, L_k = M_ee φ_k and M_qs = M_ee (on the `dim` block):
    /// the load shapes are then the end-effector parts of the shapes and the load
    /// flexibility the static one. What sagging cables over pulleys take (module docs).
    pub fn end_effector_only(shapes: &ModeShapes, ee_mass: &Matrix6<f64>) -> QuasiStaticLoad {
        let dim = shapes.dim;
        let mut mass_kg = Matrix6::zeros();
        mass_kg
            .view_mut((0, 0), (dim, dim))
            .copy_from(&ee_mass.view((0, 0), (dim, dim)));
        let participation = shapes.modes.iter().map(|m| mass_kg * m.ee).collect();
        QuasiStaticLoad {
            dim,
            participation,
            mass_kg,
            static_mass_kg: mass_kg,
        }
    }

    /// From a dense (K, M) whose first `dim` DOFs are the end-effector's and the
    /// mass-normalised eigenvectors `vectors` (columns): r = [I; −K_ii⁻¹ K_ie] by a Cholesky
    /// solve of K_ii. None when K_ii is not positive definite.
    pub fn from_dense(
        k: &DMatrix<f64>,
        m: &DMatrix<f64>,
        dim: usize,
        vectors: &DMatrix<f64>,
    ) -> Option<QuasiStaticLoad> {
        let n = k.nrows();
        let mut r = DMatrix::<f64>::zeros(n, dim);
        for d in 0..dim {
            r[(d, d)] = 1.0;
        }
        if n > dim {
            let kii = k.view((dim, dim), (n - dim, n - dim)).into_owned();
            let kie = k.view((dim, 0), (n - dim, dim)).into_owned();
            let ri = -kii.cholesky()?.solve(&kie);
            r.view_mut((dim, 0), (n - dim, dim)).copy_from(&ri);
        }
        let mr = m * &r;
        let l = vectors.transpose() * &mr;
        let mqs = r.transpose() * &mr;
        let participation = (0..l.nrows())
            .map(|j| {
                let mut v = Vector6::zeros();
                for d in 0..dim {
                    v[d] = l[(j, d)];
                }
                v
            })
            .collect();
        let mut mass_kg = Matrix6::zeros();
        for a in 0..dim {
            for b in 0..dim {
                mass_kg[(a, b)] = 0.5 * (mqs[(a, b)] + mqs[(b, a)]);
            }
        }
        Some(QuasiStaticLoad {
            dim,
            participation,
            mass_kg,
            static_mass_kg: mass_kg,
        })
    }

    /// The inverse of the end-effector's mass on the `dim` block (zeros beyond), or None
    /// when it is singular.
    fn ee_mass_inverse(&self, ee_mass: &Matrix6<f64>) -> Option<Matrix6<f64>> {
        let d = self.dim;
        let inv = ee_mass.view((0, 0), (d, d)).into_owned().try_inverse()?;
        let mut out = Matrix6::zeros();
        out.view_mut((0, 0), (d, d)).copy_from(&inv);
        Some(out)
    }

    /// The load shapes ψ_k = M_ee⁻¹ L_k (module docs; 1/√kg, zeros beyond `dim`), or None
    /// when the end-effector's mass is singular.
    pub fn load_shapes(&self, ee_mass: &Matrix6<f64>) -> Option<Vec<Vector6<f64>>> {
        let inv = self.ee_mass_inverse(ee_mass)?;
        Some(self.participation.iter().map(|l| inv * l).collect())
    }

    /// The load flexibility F_ψ = F M_s M_ee⁻¹ of the static flexibility `flexibility`
    /// (m/N; module docs: M_s = M_qs but on a sagging robot's path field), or None when the
    /// end-effector's mass is singular.
    pub fn load_flexibility(
        &self,
        flexibility: &Matrix6<f64>,
        ee_mass: &Matrix6<f64>,
    ) -> Option<Matrix6<f64>> {
        Some(flexibility * self.static_mass_kg * self.ee_mass_inverse(ee_mass)?)
    }
}

/// The convective load of a sagging robot's path (module docs): each mode's participation
/// in the six second-derivative fields and their static answer.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvectiveLoad {
    /// χ_k = (φ_kᵀ M C_i)_i of each mode (kg^½/m; the six pairs xx, yy, zz, xy, xz, yz).
    pub participation: Vec<Vector6<f64>>,
    /// S = (r_s,dᵀ M C_i)_{d,i}, kg/m (kg in a rigid body's rotational rows; zeros beyond
    /// `dim` rows).
    pub static_kg_per_m: Matrix6<f64>,
}

impl ConvectiveLoad {
    /// From the structured shapes of a pose, the second-derivative fields `second` (six
    /// entries of its `modes`) and the fixed-length field `fixed` (the same node lists),
    /// the end-effector's mass `ee_mass`. None when the node lists differ or `second` has
    /// not six fields.
    pub fn from_fields(
        shapes: &ModeShapes,
        second: &ModeShapes,
        fixed: &ModeShapes,
        ee_mass: &Matrix6<f64>,
    ) -> Option<ConvectiveLoad> {
        let pairs = second.modes.len();
        if pairs != 6 || fixed.modes.len() != shapes.dim {
            return None;
        }
        let l = shapes.mass_overlap(second, ee_mass)?;
        let participation = (0..shapes.modes.len())
            .map(|k| Vector6::from_column_slice(&l[k * pairs..(k + 1) * pairs]))
            .collect();
        let s = fixed.mass_overlap(second, ee_mass)?;
        let mut static_kg_per_m = Matrix6::zeros();
        for d in 0..shapes.dim {
            for i in 0..pairs {
                static_kg_per_m[(d, i)] = s[d * pairs + i];
            }
        }
        Some(ConvectiveLoad {
            participation,
            static_kg_per_m,
        })
    }

    /// The static answer per unit of the response's force −w: F S, m per (m²/s²), of the
    /// static flexibility `flexibility` (module docs).
    pub fn load_flexibility(&self, flexibility: &Matrix6<f64>) -> Matrix6<f64> {
        flexibility * self.static_kg_per_m
    }
}
