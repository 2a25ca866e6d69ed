//! The outcome of one estimator cycle ([`StatusCode`], also `estimator::Status`), carried
//! as `u32` in the IPC messages' `status` fields (`cablevib-ipc` re-exports this module).

/// Outcome of one estimator cycle, as carried on the wire (`u32`).
///
/// The numeric values are part of the schema: they never change and a retired code is never
/// reused. A new code may be added within the same schema version (`SCHEMA_VERSION` of `cablevib-ipc`);
/// a receiver that does not know a code ([`StatusCode::from_u32`] returns `None`) must treat
/// the sample as "not valid".
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StatusCode {
    /// Valid estimate: tensions, f1 and stiffness are those of the echoed pose.
    Ok = 0,
    /// No tension distribution satisfies T_min ≤ T ≤ T_max and the wrench balance.
    TensionInfeasible = 1,
    /// The input has a non-finite (NaN/Inf) component or is otherwise malformed, e.g. an
    /// orientation other than the identity (vector part over 1e-3 of the quaternion's norm)
    /// on a point-mass end-effector, which has none.
    InvalidInput = 2,
    /// An iterative solver (tension or eigen) stopped at its iteration limit.
    NotConverged = 3,
    /// The structure or stiffness matrix is rank deficient at this pose.
    RankDeficient = 4,
    /// The position is at an anchor (a cable shorter than 1e-6 m). A position the robot
    /// cannot hold is `TensionInfeasible`: there is no geometric pre-test of the workspace.
    OutsideWorkspace = 5,
    /// No pose has been received yet (margin queries before the first estimate).
    NoPoseYet = 6,
    /// The orientation quaternion is not of unit norm.
    NonUnitQuaternion = 7,
    /// A T_min set-point below zero, above T_max or non-finite; the previous one stays in force.
    TminOutOfRange = 8,
    /// A margin request with a required frequency outside `REQUIRED_F1_MIN_HZ`,
    /// `REQUIRED_F1_MAX_HZ` of `cablevib-ipc` (NaN included).
    InvalidRequest = 9,
    /// An internal error of the service; see its log.
    InternalError = 10,
    /// A sagging cable would go slack: its end tension is below the least any catenary
    /// through its chord can have (its tension would reach zero along it). No numbers.
    CableSlack = 11,
    /// A direction of the end-effector has no stiffness at this pose (a mechanism, e.g. the
    /// spin of a platform whose attachments lie on one axis): no natural frequency exists.
    /// The tensions are valid; f1 and the stiffness are NaN.
    Mechanism = 12,
}

impl StatusCode {
    /// Every code, in numeric order.
    pub const ALL: [StatusCode; 13] = [
        StatusCode::Ok,
        StatusCode::TensionInfeasible,
        StatusCode::InvalidInput,
        StatusCode::NotConverged,
        StatusCode::RankDeficient,
        StatusCode::OutsideWorkspace,
        StatusCode::NoPoseYet,
        StatusCode::NonUnitQuaternion,
        StatusCode::TminOutOfRange,
        StatusCode::InvalidRequest,
        StatusCode::InternalError,
        StatusCode::CableSlack,
        StatusCode::Mechanism,
    ];

    /// The wire value.
    pub const fn as_u32(self) -> u32 {
        self as u32
    }

    /// The code of a wire value; `None` for a value this build does not know.
    pub const fn from_u32(value: u32) -> Option<StatusCode> {
        // `ALL` is in numeric order without gaps (tested below): the value is the index.
        if (value as usize) < Self::ALL.len() {
            Some(Self::ALL[value as usize])
        } else {
            None
        }
    }

    /// A stable snake_case identifier (for logs and CSV output).
    pub const fn as_str(self) -> &'static str {
        match self {
            StatusCode::Ok => "ok",
            StatusCode::TensionInfeasible => "tension_infeasible",
            StatusCode::InvalidInput => "invalid_input",
            StatusCode::NotConverged => "not_converged",
            StatusCode::RankDeficient => "rank_deficient",
            StatusCode::OutsideWorkspace => "outside_workspace",
            StatusCode::NoPoseYet => "no_pose_yet",
            StatusCode::NonUnitQuaternion => "non_unit_quaternion",
            StatusCode::TminOutOfRange => "t_min_out_of_range",
            StatusCode::InvalidRequest => "invalid_request",
            StatusCode::InternalError => "internal_error",
            StatusCode::CableSlack => "cable_slack",
            StatusCode::Mechanism => "mechanism",
        }
    }

    /// `true` only for [`StatusCode::Ok`].
    pub const fn is_ok(self) -> bool {
        matches!(self, StatusCode::Ok)
    }
}

impl core::fmt::Display for StatusCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl From<StatusCode> for u32 {
    fn from(code: StatusCode) -> u32 {
        code as u32
    }
}

/// A wire status as text, without allocating: the code's name or `unknown(N)`.
pub const fn status_str(value: u32) -> StatusText {
    StatusText(value)
}

/// Displays a wire status value: the code's name, or `unknown(N)` for a code this build
/// does not know.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StatusText(pub u32);

impl core::fmt::Display for StatusText {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match StatusCode::from_u32(self.0) {
            Some(code) => f.write_str(code.as_str()),
            None => write!(f, "unknown({})", self.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_stable_values() {
        for (i, code) in StatusCode::ALL.iter().enumerate() {
            assert_eq!(
                code.as_u32(),
                i as u32,
                "ALL is in numeric order without gaps"
            );
            assert_eq!(StatusCode::from_u32(code.as_u32()), Some(*code));
        }
        assert_eq!(StatusCode::from_u32(StatusCode::ALL.len() as u32), None);
        assert_eq!(StatusCode::from_u32(u32::MAX), None);
        // The wire values are frozen.
        assert_eq!(StatusCode::Ok as u32, 0);
        assert_eq!(StatusCode::TensionInfeasible as u32, 1);
        assert_eq!(StatusCode::InvalidInput as u32, 2);
        assert_eq!(StatusCode::NotConverged as u32, 3);
        assert_eq!(StatusCode::RankDeficient as u32, 4);
        assert_eq!(StatusCode::OutsideWorkspace as u32, 5);
        assert_eq!(StatusCode::NoPoseYet as u32, 6);
    }

    #[test]
    fn names_are_unique_snake_case() {
        let mut names: Vec<&str> = StatusCode::ALL.iter().map(|c| c.as_str()).collect();
        for n in &names {
            assert!(n.chars().all(|c| c.is_ascii_lowercase() || c == '_'), "{n}");
        }
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), StatusCode::ALL.len());
        assert_eq!(status_str(4).to_string(), "rank_deficient");
        assert_eq!(status_str(999).to_string(), "unknown(999)");
    }
}
