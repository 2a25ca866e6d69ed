//! Errors of the estimator: why a cycle, a build, an inverse query or an offline analysis
//! failed, and the wire status each cycle error is reported with.

use super::Status;
use crate::cable::CableError;
use crate::input_file::{message_fixed, message_number};
use crate::kinematics::KinematicsError;
use crate::modal::sagged::SagLoadError;
use crate::modal::ModalError;
use crate::tension::{SagTensionError, TensionError};

/// Input rejected before any computation. Copy, no allocation; the Display text is what
/// the CLI and the service log print after "invalid input: ".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum RejectedInput {
    /// A pose component is NaN or infinite.
    #[error("non-finite pose")]
    NonFinitePose,
    /// The orientation quaternion is not of unit norm (within the estimator's tolerance).
    #[error("quaternion is not of unit norm")]
    NonUnitQuaternion,
    /// A T_min the scene would refuse: not finite, not > 0 or subnormal, above T_max (see
    /// [`crate::scene::check_t_min`]), or per-cable bounds of the wrong count.
    #[error("t_min not finite, ≤ 0, subnormal or above t_max")]
    TminOutOfRange,
    /// `element = "auto"`: the reference model is solvable at none of the sample poses.
    #[error("no feasible pose to choose the auto model")]
    NoFeasiblePose,
    /// A rotation (a quaternion other than the identity, see
    /// [`crate::kinematics::Pose::has_identity_orientation`]) on a point-mass end-effector,
    /// which has no orientation: refused as an orientation override is refused there.
    #[error("an orientation other than the identity on a point-mass end-effector, which has none")]
    OrientationOnPointMass,
}

impl RejectedInput {
    /// The status code this input error is reported with.
    pub fn status(&self) -> Status {
        match self {
            RejectedInput::NonFinitePose => Status::InvalidInput,
            RejectedInput::NonUnitQuaternion => Status::NonUnitQuaternion,
            RejectedInput::TminOutOfRange => Status::TminOutOfRange,
            RejectedInput::NoFeasiblePose => Status::InvalidInput,
            RejectedInput::OrientationOnPointMass => Status::InvalidInput,
        }
    }
}

/// Why a cycle's estimate is not ok (the detail behind [`Status`]). Copy, no allocation.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EstimatorError {
    /// Input rejected before any computation.
    #[error("invalid input: {0}")]
    Input(#[from] RejectedInput),
    /// Kinematics failed.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// Tension distribution failed.
    #[error(transparent)]
    Tension(#[from] TensionError),
    /// Element model failed.
    #[error(transparent)]
    Cable(#[from] CableError),
    /// Eigen solver failed.
    #[error(transparent)]
    Modal(#[from] ModalError),
    /// The structure matrix has lower rank than the scene's design pose.
    #[error("structure matrix rank {rank} < {expected}: the pose is singular")]
    RankDeficient {
        /// Rank at this pose.
        rank: u32,
        /// Rank at the scene's default pose.
        expected: u32,
    },
    /// The sagged tension distribution failed (`[effects] sag`): a slack cable, an
    /// infeasible wrench, a catenary that could not be solved, or no convergence.
    #[error(transparent)]
    Sag(#[from] SagTensionError),
    /// The sagged cables could not be loaded into the modal solver.
    #[error("sagged cable model: {0}")]
    SagModel(SagLoadError),
    /// The cycle's answer fails the estimator's own check ([`super::check_answer`]): a
    /// natural frequency, participation or static stiffness that is not finite, or a first
    /// eigenvalue whose relative residual exceeds [`super::MAX_EIGEN_RESIDUAL`]. The
    /// model's numbers left the range f64 resolves somewhere; never reported as ok.
    #[error("the answer fails its check: {what} is {} (the model's numbers are out of f64's range here)", message_number(*value))]
    Unverified {
        /// What failed (e.g. `the first eigenvalue's relative residual`, `the static stiffness`).
        what: &'static str,
        /// Its value (NaN, ±∞, or the residual).
        value: f64,
    },
    /// The static stiffness does not hold one direction of the end-effector (a mechanism):
    /// there is no natural frequency (see [`crate::modal::free_direction`]).
    #[error("a mechanism: the end-effector direction {} has no stiffness, so there is no natural frequency", FreeDirection(.direction))]
    Mechanism {
        /// The free direction: translation (m) then rotation (rad) for a rigid body, unit
        /// length; the rotational part is 0 for a point mass.
        direction: [f64; 6],
    },
}

/// Displays a free direction: its translation and rotation parts, the small entries
/// dropped (e.g. `rotation about (0, 0, 1)`).
struct FreeDirection<'a>(&'a [f64; 6]);

impl std::fmt::Display for FreeDirection<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let d = self.0;
        let part = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let (t, r) = (part(&d[..3]), part(&d[3..]));
        let unit = |v: &[f64], n: f64| {
            let c = |x: f64| if (x / n).abs() < 1e-6 { 0.0 } else { x / n };
            format!("({:.3}, {:.3}, {:.3})", c(v[0]), c(v[1]), c(v[2]))
        };
        match (t > 1e-6, r > 1e-6) {
            (true, true) => write!(
                f,
                "translation {} with rotation about {}",
                unit(&d[..3], t),
                unit(&d[3..], r)
            ),
            (false, true) => write!(f, "rotation about {}", unit(&d[3..], r)),
            _ => write!(
                f,
                "translation along {}",
                unit(&d[..3], t.max(f64::MIN_POSITIVE))
            ),
        }
    }
}

impl EstimatorError {
    /// The status code this error is reported with.
    pub fn status(&self) -> Status {
        match self {
            EstimatorError::Input(input) => input.status(),
            EstimatorError::Kinematics(KinematicsError::NonFinite) => Status::InvalidInput,
            EstimatorError::Kinematics(
                KinematicsError::CableTooShort { .. }
                | KinematicsError::AlongSwivelAxis { .. }
                | KinematicsError::InsidePulley { .. },
            ) => Status::OutsideWorkspace,
            EstimatorError::Tension(TensionError::Infeasible { .. }) => Status::TensionInfeasible,
            EstimatorError::Tension(TensionError::InvalidBounds { .. }) => Status::TminOutOfRange,
            EstimatorError::Tension(TensionError::NonFinite) => Status::InvalidInput,
            EstimatorError::Tension(
                TensionError::NotConverged { .. }
                | TensionError::ReferenceFailed { .. }
                | TensionError::ReferenceRejected { .. },
            ) => Status::NotConverged,
            EstimatorError::Cable(_) => Status::RankDeficient,
            EstimatorError::Modal(ModalError::NotPositiveDefinite(_)) => Status::RankDeficient,
            EstimatorError::Modal(_) => Status::NotConverged,
            EstimatorError::RankDeficient { .. } => Status::RankDeficient,
            EstimatorError::Sag(e) => sag_status(e),
            EstimatorError::SagModel(_) => Status::InvalidInput,
            EstimatorError::Mechanism { .. } => Status::Mechanism,
            EstimatorError::Unverified { .. } => Status::NotConverged,
        }
    }
}

/// The status of a sagged tension error: a slack cable is `CableSlack`; the QP's own
/// errors as for the chord model.
fn sag_status(e: &SagTensionError) -> Status {
    match e {
        SagTensionError::Slack { .. } => Status::CableSlack,
        SagTensionError::Tension(t) => EstimatorError::Tension(*t).status(),
        SagTensionError::Invalid { .. } => Status::InvalidInput,
        SagTensionError::Catenary { .. } | SagTensionError::NoConvergence { .. } => {
            Status::NotConverged
        }
    }
}

/// Errors of the inverse T_min query.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TminQueryError {
    /// The requirement is not finite and positive.
    #[error("required f1 {} Hz must be finite and > 0", message_number(*.0))]
    BadRequirement(f64),
    /// No feasible T_min reaches the requirement (none of the search's scan points does).
    #[error(
        "f1 ≥ {} Hz is unreachable: the most any feasible T_min gives is {} Hz (at {} N)",
        message_fixed(*required_hz, 4),
        message_fixed(*f1_max_hz, 4),
        message_fixed(*t_min_n, 3)
    )]
    Unreachable {
        /// Required, Hz.
        required_hz: f64,
        /// The largest f1 the search found, Hz.
        f1_max_hz: f64,
        /// At this T_min, N.
        t_min_n: f64,
    },
    /// The pose itself is invalid or infeasible at every T_min.
    #[error(transparent)]
    Pose(#[from] EstimatorError),
}

impl From<RejectedInput> for TminQueryError {
    fn from(e: RejectedInput) -> Self {
        TminQueryError::Pose(e.into())
    }
}

/// Errors building an estimator.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The scene's pose (its `position`, or a caller's position override) has no
    /// answer that makes the robot usable (e.g. a cable of zero length): the message names
    /// the pose, which is the scene file's default only when no other was given.
    #[error(
        "scene `{scene}` at ({}, {}, {}) m: {reason}",
        message_number(.position_m[0]),
        message_number(.position_m[1]),
        message_number(.position_m[2])
    )]
    DefaultPose {
        /// Scene name.
        scene: String,
        /// The pose's position, m.
        position_m: [f64; 3],
        /// Why.
        reason: Box<EstimatorError>,
    },
    /// A parameter is out of its bounds ([`super::EstimatorParams::check`]).
    #[error(transparent)]
    Params(#[from] super::ParamsError),
    /// The model's preallocated buffers would be over the one memory budget (sagging FEM
    /// cables hold each element's state: [`super::SAG_BYTES_PER_ELEMENT`]).
    #[error(transparent)]
    Memory(#[from] crate::memory_budget::OverBudget),
}

/// Errors of the offline reference pipeline ([`reference_analysis`](super::reference_analysis)
/// and the pose model it is built on).
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// Kinematics.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// Tensions.
    #[error(transparent)]
    Tension(#[from] TensionError),
    /// Element models.
    #[error(transparent)]
    Cable(#[from] CableError),
    /// Eigen solve.
    #[error(transparent)]
    Modal(#[from] ModalError),
    /// The auto model could not be resolved.
    #[error("auto model: {0}")]
    Auto(String),
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The wire status each input error is meant to carry.
    const STATUS_TABLE: [(RejectedInput, Status); 5] = [
        (RejectedInput::NonFinitePose, Status::InvalidInput),
        (RejectedInput::NonUnitQuaternion, Status::NonUnitQuaternion),
        (RejectedInput::TminOutOfRange, Status::TminOutOfRange),
        (RejectedInput::NoFeasiblePose, Status::InvalidInput),
        (RejectedInput::OrientationOnPointMass, Status::InvalidInput),
    ];

    /// The Display text of `EstimatorError::Input` before the enum existed (the message was
    /// a `&'static str`), one per variant.
    const OLD_TEXTS: [(RejectedInput, &str); 5] = [
        (RejectedInput::NonFinitePose, "invalid input: non-finite pose"),
        (
            RejectedInput::NonUnitQuaternion,
            "invalid input: quaternion is not of unit norm",
        ),
        (
            RejectedInput::TminOutOfRange,
            "invalid input: t_min not finite, ≤ 0, subnormal or above t_max",
        ),
        (
            RejectedInput::NoFeasiblePose,
            "invalid input: no feasible pose to choose the auto model",
        ),
        // Added after the enum (no old text): its own.
        (
            RejectedInput::OrientationOnPointMass,
            "invalid input: an orientation other than the identity on a point-mass end-effector, which has none",
        ),
    ];

    /// The status the old code derived from words in the message.
    fn status_by_words(msg: &str) -> Status {
        if msg.contains("quaternion") {
            Status::NonUnitQuaternion
        } else if msg.contains("t_min") {
            Status::TminOutOfRange
        } else if msg.contains("outside") {
            Status::OutsideWorkspace
        } else {
            Status::InvalidInput
        }
    }

    /// Fails to compile when a variant is added, until it is added here and to the tables.
    fn table_index(e: RejectedInput) -> usize {
        match e {
            RejectedInput::NonFinitePose => 0,
            RejectedInput::NonUnitQuaternion => 1,
            RejectedInput::TminOutOfRange => 2,
            RejectedInput::NoFeasiblePose => 3,
            RejectedInput::OrientationOnPointMass => 4,
        }
    }

    #[test]
    fn every_input_error_has_its_status() {
        for (input, want) in STATUS_TABLE {
            assert_eq!(input.status(), want, "{input:?}");
            assert_eq!(EstimatorError::Input(input).status(), want, "{input:?}");
            assert_eq!(
                status_by_words(&input.to_string()),
                want,
                "{input:?}: the status the message's words gave before"
            );
        }
        for (k, (input, _)) in STATUS_TABLE.iter().enumerate() {
            assert_eq!(
                table_index(*input),
                k,
                "{input:?} out of place in STATUS_TABLE"
            );
            assert_eq!(
                OLD_TEXTS[k].0, *input,
                "{input:?} out of place in OLD_TEXTS"
            );
        }
    }

    #[test]
    fn input_error_texts_are_unchanged() {
        for (input, text) in OLD_TEXTS {
            assert_eq!(EstimatorError::Input(input).to_string(), text);
            assert_eq!(
                TminQueryError::from(input).to_string(),
                text,
                "the inverse query prints the pose error transparently"
            );
        }
        let build = BuildError::DefaultPose {
            scene: "s".into(),
            position_m: [0.5, 0.0, 1.25],
            reason: Box::new(RejectedInput::NoFeasiblePose.into()),
        };
        assert_eq!(
            build.to_string(),
            "scene `s` at (0.5, 0, 1.25) m: invalid input: no feasible pose to choose the auto model"
        );
    }
}
