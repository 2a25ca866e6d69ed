//! The message types. All are `#[repr(C)]`, `Copy`, fixed size, without implicit padding
//! (padding is spelled out as `reserved*` fields that senders set to zero); their layout is
//! frozen by compile-time asserts in [`crate::layout`] and mirrored by
//! `include/cablevib_ipc.h`.

use core::fmt::Debug;

use iceoryx2::prelude::ZeroCopySend;

use crate::status::StatusCode;
use crate::{MAX_CABLES, MAX_STIFFNESS_DIM};
use cablevib::measured::MeasuredStatus;

/// What every cablevib message type provides besides its fields.
pub trait Message: ZeroCopySend + Copy + Debug + Default + PartialEq + 'static {
    /// The iceoryx2 type name, identical to the type's `#[type_name(..)]` attribute (and to
    /// `IOX2_TYPE_NAME` in the C header); it ends with `::v{SCHEMA_VERSION}`. iceoryx2 refuses to
    /// connect two ports whose type names, sizes or alignments differ.
    const TYPE_NAME: &'static str;
    /// The name of the matching struct in `include/cablevib_ipc.h`.
    const C_NAME: &'static str;
    /// The base name of the service that carries this type (see [`crate::names`]).
    const SERVICE: &'static str;
}

/// Errors of the message builders and setters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SchemaError {
    /// More per-cable values than [`MAX_CABLES`].
    #[error("{count} cables exceed MAX_CABLES = {MAX_CABLES}")]
    TooManyCables {
        /// The number of values given.
        count: usize,
    },
    /// A stiffness dimension outside 1..=[`MAX_STIFFNESS_DIM`].
    #[error("stiffness dimension {dim} is not in 1..={MAX_STIFFNESS_DIM}")]
    BadStiffnessDim {
        /// The dimension given.
        dim: usize,
    },
    /// A stiffness matrix whose length is not `dim * dim`.
    #[error("stiffness matrix of dimension {dim} needs {expected} entries, got {got}")]
    StiffnessLength {
        /// The dimension given.
        dim: usize,
        /// `dim * dim`.
        expected: usize,
        /// The number of entries given.
        got: usize,
    },
}

/// The identity orientation `[w, x, y, z] = [1, 0, 0, 0]`.
pub const IDENTITY_QUATERNION: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

// ---------------------------------------------------------------------------------------------
// PoseSample
// ---------------------------------------------------------------------------------------------

/// End-effector pose, controller → cablevib on [`SERVICE_POSE`](crate::SERVICE_POSE).
///
/// 80 bytes, alignment 8. The service estimates the latest pose; when several are queued the
/// older ones are skipped (and counted in [`EstimateSample::skipped_poses`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, ZeroCopySend)]
#[type_name("cablevib::PoseSample::v4")]
pub struct PoseSample {
    /// Sender's sequence number, incremented by one per pose; echoed by the estimate.
    pub sequence: u64,
    /// Sender's `CLOCK_MONOTONIC` time when the pose was taken, ns
    /// (see [`monotonic_now_ns`](crate::monotonic_now_ns)).
    pub timestamp_ns: u64,
    /// Position of the end-effector reference point in the base frame, m.
    pub position_m: [f64; 3],
    /// Orientation as a unit quaternion `[w, x, y, z]`; identity is `[1, 0, 0, 0]`.
    pub orientation_wxyz: [f64; 4],
    /// Reserved for flags: senders write 0, receivers ignore bits they do not know.
    pub flags: u32,
    /// Explicit padding to a multiple of 8 bytes: write 0.
    pub reserved0: u32,
}

impl PoseSample {
    /// All fields zero (note: the zero quaternion is not a valid orientation).
    pub const fn zeroed() -> PoseSample {
        PoseSample {
            sequence: 0,
            timestamp_ns: 0,
            position_m: [0.0; 3],
            orientation_wxyz: [0.0; 4],
            flags: 0,
            reserved0: 0,
        }
    }

    /// A pose with flags and padding zero.
    pub const fn new(
        sequence: u64,
        timestamp_ns: u64,
        position_m: [f64; 3],
        orientation_wxyz: [f64; 4],
    ) -> PoseSample {
        PoseSample {
            sequence,
            timestamp_ns,
            position_m,
            orientation_wxyz,
            flags: 0,
            reserved0: 0,
        }
    }

    /// Every position and orientation component is finite.
    pub fn is_finite(&self) -> bool {
        self.position_m
            .iter()
            .chain(&self.orientation_wxyz)
            .all(|v| v.is_finite())
    }

    /// Euclidean norm of the quaternion (1 for a valid orientation).
    pub fn quaternion_norm(&self) -> f64 {
        self.orientation_wxyz
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
    }

    /// The quaternion's norm is 1 within `tol` (false when it is not finite).
    pub fn has_unit_quaternion(&self, tol: f64) -> bool {
        (self.quaternion_norm() - 1.0).abs() <= tol
    }

    /// The cheap checks a receiver makes before estimating: finite
    /// ([`StatusCode::InvalidInput`] otherwise), then unit quaternion within `tol`
    /// ([`StatusCode::NonUnitQuaternion`]). Workspace checks need the scene and are the
    /// estimator's.
    pub fn validate(&self, quaternion_tol: f64) -> Result<(), StatusCode> {
        if !self.is_finite() {
            Err(StatusCode::InvalidInput)
        } else if !self.has_unit_quaternion(quaternion_tol) {
            Err(StatusCode::NonUnitQuaternion)
        } else {
            Ok(())
        }
    }
}

impl Default for PoseSample {
    /// Sequence 0 at the origin with the identity orientation.
    fn default() -> PoseSample {
        PoseSample::new(0, 0, [0.0; 3], IDENTITY_QUATERNION)
    }
}

impl Message for PoseSample {
    const TYPE_NAME: &'static str = "cablevib::PoseSample::v4";
    const C_NAME: &'static str = "cablevib_pose_sample_t";
    const SERVICE: &'static str = crate::SERVICE_POSE;
}

// ---------------------------------------------------------------------------------------------
// TminSetpoint
// ---------------------------------------------------------------------------------------------

/// Minimum cable tension set-point, controller → cablevib on
/// [`SERVICE_T_MIN`](crate::SERVICE_T_MIN). It applies from the next estimator cycle on.
///
/// 160 bytes, alignment 8. With `per_cable_count == 0` every cable uses `t_min_n`; otherwise
/// cable `i < per_cable_count` uses `per_cable_t_min_n[i]` and the others `t_min_n`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, ZeroCopySend)]
#[type_name("cablevib::TminSetpoint::v4")]
pub struct TminSetpoint {
    /// Sender's sequence number, incremented by one per set-point.
    pub sequence: u64,
    /// Sender's `CLOCK_MONOTONIC` time, ns.
    pub timestamp_ns: u64,
    /// Minimum tension of every cable without a per-cable value, N.
    pub t_min_n: f64,
    /// Number of valid entries of `per_cable_t_min_n` (0 = use `t_min_n` for all).
    pub per_cable_count: u32,
    /// Explicit padding: write 0.
    pub reserved0: u32,
    /// Per-cable minimum tensions, N; entries at and beyond `per_cable_count` are ignored.
    pub per_cable_t_min_n: [f64; MAX_CABLES],
}

impl TminSetpoint {
    /// All fields zero (a uniform T_min of 0 N).
    pub const fn zeroed() -> TminSetpoint {
        TminSetpoint {
            sequence: 0,
            timestamp_ns: 0,
            t_min_n: 0.0,
            per_cable_count: 0,
            reserved0: 0,
            per_cable_t_min_n: [0.0; MAX_CABLES],
        }
    }

    /// The same minimum tension `t_min_n` (N) for every cable.
    pub const fn uniform(sequence: u64, timestamp_ns: u64, t_min_n: f64) -> TminSetpoint {
        let mut s = TminSetpoint::zeroed();
        s.sequence = sequence;
        s.timestamp_ns = timestamp_ns;
        s.t_min_n = t_min_n;
        s
    }

    /// Per-cable minimum tensions `per_cable_n` (N) for the first cables, `t_min_n` for the
    /// others. Fails when `per_cable_n` has more than [`MAX_CABLES`] values.
    pub fn per_cable(
        sequence: u64,
        timestamp_ns: u64,
        t_min_n: f64,
        per_cable_n: &[f64],
    ) -> Result<TminSetpoint, SchemaError> {
        if per_cable_n.len() > MAX_CABLES {
            return Err(SchemaError::TooManyCables {
                count: per_cable_n.len(),
            });
        }
        let mut s = TminSetpoint::uniform(sequence, timestamp_ns, t_min_n);
        s.per_cable_t_min_n[..per_cable_n.len()].copy_from_slice(per_cable_n);
        s.per_cable_count = per_cable_n.len() as u32;
        Ok(s)
    }

    /// The valid per-cable values (empty for a uniform set-point; at most [`MAX_CABLES`]).
    pub fn per_cable_values(&self) -> &[f64] {
        let n = (self.per_cable_count as usize).min(MAX_CABLES);
        &self.per_cable_t_min_n[..n]
    }

    /// The minimum tension of cable `cable`, N.
    pub fn t_min_for(&self, cable: usize) -> f64 {
        self.per_cable_values()
            .get(cable)
            .copied()
            .unwrap_or(self.t_min_n)
    }

    /// `per_cable_count ≤ MAX_CABLES` and every value in use finite and ≥ 0. The upper bound
    /// (T_max) is the scene's and is checked by the receiver.
    pub fn is_well_formed(&self) -> bool {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        self.per_cable_count as usize <= MAX_CABLES
            && ok(self.t_min_n)
            && self.per_cable_values().iter().all(|&v| ok(v))
    }
}

impl Default for TminSetpoint {
    /// [`TminSetpoint::zeroed`].
    fn default() -> TminSetpoint {
        TminSetpoint::zeroed()
    }
}

impl Message for TminSetpoint {
    const TYPE_NAME: &'static str = "cablevib::TminSetpoint::v4";
    const C_NAME: &'static str = "cablevib_t_min_setpoint_t";
    const SERVICE: &'static str = crate::SERVICE_T_MIN;
}

// ---------------------------------------------------------------------------------------------
// EstimateSample
// ---------------------------------------------------------------------------------------------

/// The smallest required f1 a margin request may carry, Hz (a period of ~12 days). Below
/// it the margin ratio `f1 / required` of a finite f1 overflows to +∞ (5e-324 Hz did): no
/// cable robot's vibration requirement is that slow, so smaller values are refused.
pub const REQUIRED_F1_MIN_HZ: f64 = 1e-6;
/// The largest required f1 a margin request may carry, Hz: far above any cable robot's first
/// mode (tens of Hz; the stiffest cable's axial modes are kHz), so that a larger value is a
/// client's mistake and is refused rather than answered with a margin of −1e308 Hz.
pub const REQUIRED_F1_MAX_HZ: f64 = 1e6;

/// [`EstimateSample::ee_mode_age_cycles`] when no end-effector mode is known.
pub const EE_MODE_AGE_UNKNOWN: u32 = u32::MAX;
/// [`EstimateSample::measured_age_ns`] when no frequency is measured.
pub const MEASURED_AGE_UNKNOWN: u64 = u64::MAX;
/// [`MarginResponse::t_min_required_age_cycles`] when no T_min is known for the requirement.
pub const T_MIN_AGE_UNKNOWN: u32 = u32::MAX;

/// One estimator cycle's result, cablevib → controller on
/// [`SERVICE_ESTIMATE`](crate::SERVICE_ESTIMATE).
///
/// 592 bytes, alignment 8. It answers the pose whose `sequence` and `timestamp_ns` it echoes
/// in `pose_sequence` / `pose_timestamp_ns`; the controller compares them with the pose it
/// last sent to tell a fresh estimate from a stale one. The numeric fields are meaningful only
/// when `status` is [`StatusCode::Ok`]; otherwise frequencies are NaN and tensions and
/// stiffness may be zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, ZeroCopySend)]
#[type_name("cablevib::EstimateSample::v4")]
pub struct EstimateSample {
    /// `sequence` of the pose this estimate answers.
    pub pose_sequence: u64,
    /// `timestamp_ns` of that pose (sender's clock), ns.
    pub pose_timestamp_ns: u64,
    /// cablevib's `CLOCK_MONOTONIC` when it took the pose, ns.
    pub receive_timestamp_ns: u64,
    /// cablevib's `CLOCK_MONOTONIC` just before publishing, ns (the sender timestamp).
    pub publish_timestamp_ns: u64,
    /// A [`StatusCode`] as `u32`.
    pub status: u32,
    /// Number of valid entries of `tensions_n` (the scene's cable count).
    pub cable_count: u32,
    /// Cable tensions, N; entries at and beyond `cable_count` are zero.
    pub tensions_n: [f64; MAX_CABLES],
    /// First natural frequency of the robot at this pose, Hz.
    pub f1_hz: f64,
    /// Frequency of the lowest mode dominated by end-effector motion (end-effector
    /// participation ≥ the scene's threshold), Hz, as of `ee_mode_age_cycles` estimates
    /// ago; NaN when none is known.
    pub ee_mode_hz: f64,
    /// Dimension of the end-effector stiffness matrix: 3 (translations x, y, z) or 6
    /// (x, y, z, then rotations θx, θy, θz).
    pub stiffness_dim: u32,
    /// How many cycles (estimates) old `ee_mode_hz` is: 0 = computed and certified at
    /// this pose; k > 0 = the answer of k estimates ago, while the work that did not fit
    /// in the cycle's evaluation budget (an end-effector band rescan, a cold
    /// re-identification) goes on over the next cycles; [`EE_MODE_AGE_UNKNOWN`]
    /// (`u32::MAX`) = no end-effector mode known (`ee_mode_hz` is NaN). A number in
    /// `ee_mode_hz` always reached the scene's participation threshold when computed.
    pub ee_mode_age_cycles: u32,
    /// End-effector stiffness matrix, row-major and packed: entry (r, c) is
    /// `stiffness[r * stiffness_dim + c]`; entries at and beyond `stiffness_dim²` are zero.
    /// Units N/m (translation block), N·m/rad (rotation block), N/rad (coupling).
    pub stiffness: [f64; MAX_STIFFNESS_DIM * MAX_STIFFNESS_DIM],
    /// Time spent computing this estimate, ns.
    pub compute_ns: u64,
    /// Evaluations of the dynamic stiffness D(λ) in this cycle (first mode and end-effector
    /// mode): never more than the service's per-cycle budget.
    pub eigen_evaluations: u32,
    /// Iterations spent on the tension distribution.
    pub tension_iterations: u32,
    /// Relative residual of the first natural frequency (dimensionless):
    /// |μ₁(D(λ))| / (λ·max|D'(λ)|) at the eigen solver's last iterate λ, the smallest
    /// eigenvalue of the condensed dynamic stiffness against the inertia term it cancels;
    /// to first order the relative distance of λ to the root. ≤ 1e-9 on converged answers.
    pub eigen_residual: f64,
    /// Poses skipped since the service started because a newer one was queued.
    pub skipped_poses: u64,
    /// The service's estimate count: 1 for the first estimate it publishes, one more for each
    /// next one. A subscriber that sees a gap (for one publisher) lost that many estimates in
    /// its queue; a restarted service starts again from 1.
    pub sequence: u64,
    /// The dominant measured frequency near `f1_hz`, Hz, from the vibration input
    /// ([`VibrationSample`]s on [`SERVICE_VIBRATION`](crate::SERVICE_VIBRATION)); NaN unless
    /// `measured_f1_status` is [`MeasuredStatus::Ok`].
    pub measured_f1_hz: f64,
    /// `f1_hz − measured_f1_hz`, Hz (model − measured); NaN when either is absent.
    pub f1_residual_hz: f64,
    /// The dominant measured frequency near `ee_mode_hz`, Hz; NaN unless
    /// `measured_ee_mode_status` is [`MeasuredStatus::Ok`].
    pub measured_ee_mode_hz: f64,
    /// `ee_mode_hz − measured_ee_mode_hz`, Hz; NaN when either is absent.
    pub ee_mode_residual_hz: f64,
    /// Age of the measured frequencies: `receive_timestamp_ns` minus the centre of the
    /// window they describe (the vibration samples' clock), ns; [`MEASURED_AGE_UNKNOWN`]
    /// (`u64::MAX`) when neither is measured.
    pub measured_age_ns: u64,
    /// A [`MeasuredStatus`] as `u32`: why `measured_f1_hz` is or is not a number
    /// (`no_input` while no vibration arrives).
    pub measured_f1_status: u32,
    /// A [`MeasuredStatus`] as `u32` for `measured_ee_mode_hz`.
    pub measured_ee_mode_status: u32,
    /// Vibration samples taken since the service started.
    pub vibration_samples: u64,
    /// Vibration samples refused since the service started (a component not finite or beyond
    /// ±1e6 m/s², a sequence or timestamp not after the previous sample's).
    pub vibration_refused: u64,
    /// Vibration samples never received since the service started (gaps in the sequence).
    pub vibration_lost: u64,
}

impl EstimateSample {
    /// All fields zero. Beware: status 0 is [`StatusCode::Ok`]; [`Default`] is the safe
    /// "no estimate" value.
    pub const fn zeroed() -> EstimateSample {
        EstimateSample {
            pose_sequence: 0,
            pose_timestamp_ns: 0,
            receive_timestamp_ns: 0,
            publish_timestamp_ns: 0,
            status: 0,
            cable_count: 0,
            tensions_n: [0.0; MAX_CABLES],
            f1_hz: 0.0,
            ee_mode_hz: 0.0,
            stiffness_dim: 0,
            ee_mode_age_cycles: 0,
            stiffness: [0.0; MAX_STIFFNESS_DIM * MAX_STIFFNESS_DIM],
            compute_ns: 0,
            eigen_evaluations: 0,
            tension_iterations: 0,
            eigen_residual: 0.0,
            skipped_poses: 0,
            sequence: 0,
            measured_f1_hz: 0.0,
            f1_residual_hz: 0.0,
            measured_ee_mode_hz: 0.0,
            ee_mode_residual_hz: 0.0,
            measured_age_ns: 0,
            measured_f1_status: 0,
            measured_ee_mode_status: 0,
            vibration_samples: 0,
            vibration_refused: 0,
            vibration_lost: 0,
        }
    }

    /// An estimate carrying `status` and no values (frequencies and residual NaN, no cables),
    /// for a pose that could not be estimated.
    pub const fn with_status(status: StatusCode) -> EstimateSample {
        let mut e = EstimateSample::zeroed();
        e.status = status as u32;
        e.f1_hz = f64::NAN;
        e.ee_mode_hz = f64::NAN;
        e.ee_mode_age_cycles = EE_MODE_AGE_UNKNOWN;
        e.eigen_residual = f64::NAN;
        e.set_measured_none(MeasuredStatus::NoInput);
        e
    }

    /// No measured frequencies, for `status` (both tracks): NaN frequencies and residuals,
    /// age [`MEASURED_AGE_UNKNOWN`].
    pub const fn set_measured_none(&mut self, status: MeasuredStatus) {
        self.measured_f1_hz = f64::NAN;
        self.f1_residual_hz = f64::NAN;
        self.measured_ee_mode_hz = f64::NAN;
        self.ee_mode_residual_hz = f64::NAN;
        self.measured_age_ns = MEASURED_AGE_UNKNOWN;
        self.measured_f1_status = status as u32;
        self.measured_ee_mode_status = status as u32;
    }

    /// The status as a [`StatusCode`] (`None` for a code this build does not know).
    pub const fn status_code(&self) -> Option<StatusCode> {
        StatusCode::from_u32(self.status)
    }

    /// The status is [`StatusCode::Ok`].
    pub const fn is_ok(&self) -> bool {
        self.status == StatusCode::Ok as u32
    }

    /// This estimate answers `pose` (same sequence and timestamp).
    pub const fn answers(&self, pose: &PoseSample) -> bool {
        self.pose_sequence == pose.sequence && self.pose_timestamp_ns == pose.timestamp_ns
    }

    /// The valid tensions, N (`cable_count` entries, at most [`MAX_CABLES`]).
    pub fn tensions(&self) -> &[f64] {
        &self.tensions_n[..(self.cable_count as usize).min(MAX_CABLES)]
    }

    /// Sets `tensions_n` and `cable_count` from `tensions_n` (N), zeroing the unused entries.
    pub fn set_tensions(&mut self, tensions_n: &[f64]) -> Result<(), SchemaError> {
        if tensions_n.len() > MAX_CABLES {
            return Err(SchemaError::TooManyCables {
                count: tensions_n.len(),
            });
        }
        self.tensions_n = [0.0; MAX_CABLES];
        self.tensions_n[..tensions_n.len()].copy_from_slice(tensions_n);
        self.cable_count = tensions_n.len() as u32;
        Ok(())
    }

    /// The packed row-major `stiffness_dim × stiffness_dim` stiffness matrix (empty when the
    /// dimension is 0 or invalid).
    pub fn stiffness_matrix(&self) -> &[f64] {
        let d = self.stiffness_dim as usize;
        if d > MAX_STIFFNESS_DIM {
            return &[];
        }
        &self.stiffness[..d * d]
    }

    /// Stiffness entry (`row`, `col`), or `None` outside the matrix.
    pub fn stiffness_at(&self, row: usize, col: usize) -> Option<f64> {
        let d = self.stiffness_dim as usize;
        (d <= MAX_STIFFNESS_DIM && row < d && col < d).then(|| self.stiffness[row * d + col])
    }

    /// Sets `stiffness_dim` and `stiffness` from a row-major `dim × dim` matrix, zeroing the
    /// unused entries.
    pub fn set_stiffness(&mut self, dim: usize, row_major: &[f64]) -> Result<(), SchemaError> {
        if dim == 0 || dim > MAX_STIFFNESS_DIM {
            return Err(SchemaError::BadStiffnessDim { dim });
        }
        if row_major.len() != dim * dim {
            return Err(SchemaError::StiffnessLength {
                dim,
                expected: dim * dim,
                got: row_major.len(),
            });
        }
        self.stiffness = [0.0; MAX_STIFFNESS_DIM * MAX_STIFFNESS_DIM];
        self.stiffness[..dim * dim].copy_from_slice(row_major);
        self.stiffness_dim = dim as u32;
        Ok(())
    }

    /// Time from the pose's timestamp to `now_ns` (same clock), ns; 0 if `now_ns` is earlier.
    pub const fn age_ns(&self, now_ns: u64) -> u64 {
        now_ns.saturating_sub(self.pose_timestamp_ns)
    }
}

impl Default for EstimateSample {
    /// [`EstimateSample::with_status`]`(`[`StatusCode::NoPoseYet`]`)`.
    fn default() -> EstimateSample {
        EstimateSample::with_status(StatusCode::NoPoseYet)
    }
}

impl Message for EstimateSample {
    const TYPE_NAME: &'static str = "cablevib::EstimateSample::v4";
    const C_NAME: &'static str = "cablevib_estimate_sample_t";
    const SERVICE: &'static str = crate::SERVICE_ESTIMATE;
}

// ---------------------------------------------------------------------------------------------
// Margin request / response
// ---------------------------------------------------------------------------------------------

/// Vibration-margin query, controller → cablevib on the request-response service
/// [`SERVICE_MARGIN`](crate::SERVICE_MARGIN). 24 bytes, alignment 8.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, ZeroCopySend)]
#[type_name("cablevib::MarginRequest::v4")]
pub struct MarginRequest {
    /// Requester's sequence number; echoed as [`MarginResponse::request_sequence`].
    pub sequence: u64,
    /// Requester's `CLOCK_MONOTONIC` time, ns.
    pub timestamp_ns: u64,
    /// The first natural frequency the controller needs to stay above, Hz, in
    /// [[`REQUIRED_F1_MIN_HZ`], [`REQUIRED_F1_MAX_HZ`]] (outside: status `invalid_request`).
    pub required_f1_hz: f64,
}

impl MarginRequest {
    /// All fields zero.
    pub const fn zeroed() -> MarginRequest {
        MarginRequest {
            sequence: 0,
            timestamp_ns: 0,
            required_f1_hz: 0.0,
        }
    }

    /// A request for margin against `required_f1_hz` (Hz).
    pub const fn new(sequence: u64, timestamp_ns: u64, required_f1_hz: f64) -> MarginRequest {
        MarginRequest {
            sequence,
            timestamp_ns,
            required_f1_hz,
        }
    }

    /// `required_f1_hz` is within [[`REQUIRED_F1_MIN_HZ`], [`REQUIRED_F1_MAX_HZ`]] (so finite
    /// and positive, and the margin ratio of a finite f1 is finite).
    pub fn is_valid(&self) -> bool {
        (REQUIRED_F1_MIN_HZ..=REQUIRED_F1_MAX_HZ).contains(&self.required_f1_hz)
    }
}

impl Default for MarginRequest {
    /// [`MarginRequest::zeroed`].
    fn default() -> MarginRequest {
        MarginRequest::zeroed()
    }
}

impl Message for MarginRequest {
    const TYPE_NAME: &'static str = "cablevib::MarginRequest::v4";
    const C_NAME: &'static str = "cablevib_margin_request_t";
    const SERVICE: &'static str = crate::SERVICE_MARGIN;
}

/// Answer to a [`MarginRequest`] for the latest estimated pose. 64 bytes, alignment 8.
///
/// Frequencies and margins are NaN unless `status` is [`StatusCode::Ok`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, ZeroCopySend)]
#[type_name("cablevib::MarginResponse::v4")]
pub struct MarginResponse {
    /// `sequence` of the request answered.
    pub request_sequence: u64,
    /// `sequence` of the pose whose estimate the answer is based on (0 if none).
    pub pose_sequence: u64,
    /// A [`StatusCode`] as `u32` (that of the latest estimate, or [`StatusCode::NoPoseYet`],
    /// or [`StatusCode::InvalidRequest`], or that of a failed inverse T_min search at an ok
    /// estimate).
    pub status: u32,
    /// How many estimates old `t_min_required_n` is: 0 = computed at the pose of
    /// `pose_sequence`; k > 0 = at the pose k estimates earlier (the inverse search runs
    /// beside the estimate loop and answers the newest requirement);
    /// [`T_MIN_AGE_UNKNOWN`] (`u32::MAX`) = not known for this requirement (NaN).
    pub t_min_required_age_cycles: u32,
    /// First natural frequency at that pose, Hz.
    pub f1_hz: f64,
    /// `f1_hz − required_f1_hz`, Hz (negative: below the requirement).
    pub margin_hz: f64,
    /// `f1_hz / required_f1_hz` (below 1: below the requirement).
    pub margin_ratio: f64,
    /// The smallest cable tension floor (the same for every cable) at which f1 reaches this
    /// request's requirement, N, at the pose `t_min_required_age_cycles` estimates before
    /// `pose_sequence`; +∞ when no feasible T_min reaches it; NaN while not known (not
    /// computed yet for this requirement). When the search failed at that pose the response
    /// carries the search's status instead of `Ok` (and its age).
    pub t_min_required_n: f64,
    /// cablevib's `CLOCK_MONOTONIC` when answering, ns.
    pub timestamp_ns: u64,
}

impl MarginResponse {
    /// All fields zero. Beware: status 0 is [`StatusCode::Ok`]; [`Default`] is the safe
    /// "no estimate" value.
    pub const fn zeroed() -> MarginResponse {
        MarginResponse {
            request_sequence: 0,
            pose_sequence: 0,
            status: 0,
            t_min_required_age_cycles: 0,
            f1_hz: 0.0,
            margin_hz: 0.0,
            margin_ratio: 0.0,
            t_min_required_n: 0.0,
            timestamp_ns: 0,
        }
    }

    /// A response carrying `status` and no values (all frequencies, margins and
    /// `t_min_required_n` NaN).
    pub const fn with_status(
        request: &MarginRequest,
        status: StatusCode,
        timestamp_ns: u64,
    ) -> MarginResponse {
        MarginResponse {
            request_sequence: request.sequence,
            pose_sequence: 0,
            status: status as u32,
            t_min_required_age_cycles: T_MIN_AGE_UNKNOWN,
            f1_hz: f64::NAN,
            margin_hz: f64::NAN,
            margin_ratio: f64::NAN,
            t_min_required_n: f64::NAN,
            timestamp_ns,
        }
    }

    /// The answer to `request` given the latest estimate's `f1_hz` (Hz) for pose
    /// `pose_sequence`: `margin_hz = f1 − required`, `margin_ratio = f1 / required`.
    pub fn from_f1(
        request: &MarginRequest,
        pose_sequence: u64,
        status: StatusCode,
        f1_hz: f64,
        t_min_required_n: f64,
        timestamp_ns: u64,
    ) -> MarginResponse {
        MarginResponse {
            request_sequence: request.sequence,
            pose_sequence,
            status: status as u32,
            t_min_required_age_cycles: if t_min_required_n.is_nan() {
                T_MIN_AGE_UNKNOWN
            } else {
                0
            },
            f1_hz,
            margin_hz: f1_hz - request.required_f1_hz,
            margin_ratio: f1_hz / request.required_f1_hz,
            t_min_required_n,
            timestamp_ns,
        }
    }

    /// The status as a [`StatusCode`] (`None` for a code this build does not know).
    pub const fn status_code(&self) -> Option<StatusCode> {
        StatusCode::from_u32(self.status)
    }

    /// The status is [`StatusCode::Ok`].
    pub const fn is_ok(&self) -> bool {
        self.status == StatusCode::Ok as u32
    }
}

impl Default for MarginResponse {
    /// No request answered, status [`StatusCode::NoPoseYet`], values NaN.
    fn default() -> MarginResponse {
        MarginResponse::with_status(&MarginRequest::zeroed(), StatusCode::NoPoseYet, 0)
    }
}

impl Message for MarginResponse {
    const TYPE_NAME: &'static str = "cablevib::MarginResponse::v4";
    const C_NAME: &'static str = "cablevib_margin_response_t";
    const SERVICE: &'static str = crate::SERVICE_MARGIN;
}

// ---------------------------------------------------------------------------------------------
// VibrationSample
// ---------------------------------------------------------------------------------------------

/// [`VibrationSample::flags`] bit: `angular_velocity_rad_s` holds a measurement (an IMU);
/// clear for an accelerometer alone.
pub const VIBRATION_FLAG_ANGULAR_VELOCITY: u32 = 1;

/// One sample of a sensor on the platform (an accelerometer or IMU), sensor → cablevib on
/// [`SERVICE_VIBRATION`](crate::SERVICE_VIBRATION). Optional: without it every estimate
/// says `no_input` in its measured fields and is otherwise unchanged.
///
/// 72 bytes, alignment 8. `sequence` gives the sample's place in the sensor's uniform sample
/// grid (a gap is a lost sample) and `timestamp_ns` the time it was taken (the sensor's time,
/// not its arrival), from which the service learns the sample period: send every sample, in
/// order.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, ZeroCopySend)]
#[type_name("cablevib::VibrationSample::v4")]
pub struct VibrationSample {
    /// Sender's sequence number, incremented by one per sample.
    pub sequence: u64,
    /// `CLOCK_MONOTONIC` when the sample was taken, ns.
    pub timestamp_ns: u64,
    /// Specific force (acceleration minus gravity, what an accelerometer reads) along three
    /// axes fixed to the platform (the sensor's own), m/s². The measured frequencies use the
    /// sum of the three axes' power, which does not depend on how the sensor is turned.
    pub acceleration_m_s2: [f64; 3],
    /// Angular velocity about the same axes, rad/s, when the
    /// [`VIBRATION_FLAG_ANGULAR_VELOCITY`] flag is set (zero otherwise). Carried for
    /// recording and offline identification; the live estimate uses the accelerations.
    pub angular_velocity_rad_s: [f64; 3],
    /// [`VIBRATION_FLAG_ANGULAR_VELOCITY`]; other bits: write 0, receivers ignore them.
    pub flags: u32,
    /// Explicit padding: write 0.
    pub reserved0: u32,
}

impl VibrationSample {
    /// All fields zero.
    pub const fn zeroed() -> VibrationSample {
        VibrationSample {
            sequence: 0,
            timestamp_ns: 0,
            acceleration_m_s2: [0.0; 3],
            angular_velocity_rad_s: [0.0; 3],
            flags: 0,
            reserved0: 0,
        }
    }

    /// An accelerometer sample (no angular velocity).
    pub const fn acceleration(
        sequence: u64,
        timestamp_ns: u64,
        acceleration_m_s2: [f64; 3],
    ) -> VibrationSample {
        VibrationSample {
            sequence,
            timestamp_ns,
            acceleration_m_s2,
            angular_velocity_rad_s: [0.0; 3],
            flags: 0,
            reserved0: 0,
        }
    }

    /// An IMU sample: accelerations (m/s²) and angular velocity (rad/s).
    pub const fn imu(
        sequence: u64,
        timestamp_ns: u64,
        acceleration_m_s2: [f64; 3],
        angular_velocity_rad_s: [f64; 3],
    ) -> VibrationSample {
        VibrationSample {
            sequence,
            timestamp_ns,
            acceleration_m_s2,
            angular_velocity_rad_s,
            flags: VIBRATION_FLAG_ANGULAR_VELOCITY,
            reserved0: 0,
        }
    }
}

impl Default for VibrationSample {
    /// [`VibrationSample::zeroed`].
    fn default() -> VibrationSample {
        VibrationSample::zeroed()
    }
}

impl Message for VibrationSample {
    const TYPE_NAME: &'static str = "cablevib::VibrationSample::v4";
    const C_NAME: &'static str = "cablevib_vibration_sample_t";
    const SERVICE: &'static str = crate::SERVICE_VIBRATION;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_validation() {
        let p = PoseSample::new(1, 2, [0.1, 0.2, 0.3], IDENTITY_QUATERNION);
        assert!(p.is_finite());
        assert_eq!(p.validate(1e-9), Ok(()));
        let mut bad = p;
        bad.position_m[1] = f64::NAN;
        assert_eq!(bad.validate(1e-9), Err(StatusCode::InvalidInput));
        bad = p;
        bad.orientation_wxyz[3] = f64::INFINITY;
        assert_eq!(bad.validate(1e-9), Err(StatusCode::InvalidInput));
        bad = p;
        bad.orientation_wxyz = [1.0, 0.1, 0.0, 0.0];
        assert_eq!(bad.validate(1e-6), Err(StatusCode::NonUnitQuaternion));
        assert_eq!(
            PoseSample::zeroed().validate(1e-6),
            Err(StatusCode::NonUnitQuaternion)
        );
        assert_eq!(PoseSample::default().validate(0.0), Ok(()));
    }

    #[test]
    fn t_min_setpoint() {
        let u = TminSetpoint::uniform(3, 4, 10.0);
        assert!(u.per_cable_values().is_empty());
        assert_eq!(u.t_min_for(7), 10.0);
        assert!(u.is_well_formed());

        let p = TminSetpoint::per_cable(5, 6, 10.0, &[1.0, 2.0]).unwrap();
        assert_eq!(p.per_cable_values(), &[1.0, 2.0]);
        assert_eq!(
            (p.t_min_for(0), p.t_min_for(1), p.t_min_for(2)),
            (1.0, 2.0, 10.0)
        );
        assert!(p.is_well_formed());

        assert_eq!(
            TminSetpoint::per_cable(0, 0, 1.0, &[0.0; MAX_CABLES + 1]),
            Err(SchemaError::TooManyCables {
                count: MAX_CABLES + 1
            })
        );
        let mut bad = p;
        bad.per_cable_t_min_n[1] = -1.0;
        assert!(!bad.is_well_formed());
        bad = p;
        bad.per_cable_count = MAX_CABLES as u32 + 1;
        assert!(!bad.is_well_formed());
        assert_eq!(
            bad.per_cable_values().len(),
            MAX_CABLES,
            "clamped, never panics"
        );
        assert!(!TminSetpoint::uniform(0, 0, f64::NAN).is_well_formed());
    }

    #[test]
    fn estimate_accessors() {
        let mut e = EstimateSample::default();
        assert_eq!(e.status_code(), Some(StatusCode::NoPoseYet));
        assert!(!e.is_ok() && e.f1_hz.is_nan());
        assert!(EstimateSample::zeroed().is_ok());

        e.set_tensions(&[1.0, 2.0, 3.0]).unwrap();
        assert_eq!(e.tensions(), &[1.0, 2.0, 3.0]);
        e.set_tensions(&[4.0]).unwrap();
        assert_eq!(e.tensions(), &[4.0]);
        assert_eq!(e.tensions_n[1], 0.0, "unused entries zeroed");
        assert!(e.set_tensions(&[0.0; MAX_CABLES + 1]).is_err());

        let k: Vec<f64> = (0..9).map(f64::from).collect();
        e.set_stiffness(3, &k).unwrap();
        assert_eq!(e.stiffness_matrix(), &k[..]);
        assert_eq!(e.stiffness_at(1, 2), Some(5.0));
        assert_eq!(e.stiffness_at(3, 0), None);
        assert_eq!(
            e.set_stiffness(3, &k[..8]),
            Err(SchemaError::StiffnessLength {
                dim: 3,
                expected: 9,
                got: 8
            })
        );
        assert_eq!(
            e.set_stiffness(7, &[]),
            Err(SchemaError::BadStiffnessDim { dim: 7 })
        );
        e.stiffness_dim = 99;
        assert!(e.stiffness_matrix().is_empty() && e.stiffness_at(0, 0).is_none());
        e.cable_count = 1000;
        assert_eq!(e.tensions().len(), MAX_CABLES);

        let pose = PoseSample::new(42, 1_000, [0.0; 3], IDENTITY_QUATERNION);
        e.pose_sequence = 42;
        e.pose_timestamp_ns = 1_000;
        assert!(e.answers(&pose));
        assert!(!e.answers(&PoseSample {
            sequence: 43,
            ..pose
        }));
        assert_eq!(e.age_ns(1_500), 500);
        assert_eq!(e.age_ns(10), 0);
    }

    #[test]
    fn margin() {
        let req = MarginRequest::new(9, 100, 4.0);
        assert!(req.is_valid());
        assert!(!MarginRequest::new(0, 0, 0.0).is_valid());
        assert!(!MarginRequest::new(0, 0, f64::NAN).is_valid());
        // A degenerate requirement would give a ratio of +inf or a margin of -1e308 Hz.
        for bad in [5e-324, 1e-7, 2e6, f64::INFINITY, -1.0] {
            assert!(!MarginRequest::new(0, 0, bad).is_valid(), "{bad}");
        }
        for good in [REQUIRED_F1_MIN_HZ, 8.0, REQUIRED_F1_MAX_HZ] {
            assert!(MarginRequest::new(0, 0, good).is_valid(), "{good}");
        }
        let r = MarginResponse::from_f1(&req, 7, StatusCode::Ok, 5.0, f64::NAN, 200);
        assert_eq!((r.request_sequence, r.pose_sequence), (9, 7));
        assert_eq!((r.margin_hz, r.margin_ratio), (1.0, 1.25));
        assert!(r.is_ok() && r.t_min_required_n.is_nan());
        let none = MarginResponse::with_status(&req, StatusCode::NoPoseYet, 300);
        assert_eq!(none.status_code(), Some(StatusCode::NoPoseYet));
        assert_eq!(none.request_sequence, 9);
        assert!(none.f1_hz.is_nan() && none.margin_hz.is_nan());
        assert_eq!(
            MarginResponse::default().status_code(),
            Some(StatusCode::NoPoseYet)
        );
    }
}
