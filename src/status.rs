//! The outcome of one estimator cycle ([`StatusCode`], also `estimator::Status`), carried
//! as `u32` in the IPC messages' `status` fields (`cablevib-ipc` re-exports this module).

/// Defines a wire status enum ([`StatusCode`] here; the measured-vibration codes of
/// the measured-frequency module's too) from one list of `variant = code, "name"` rows (each with its
/// docs): the enum with those wire values, `ALL` in the list's order, `as_str`, `as_u32`,
/// `from_u32` and `Display`. One list, so that a new code cannot be added to the enum and
/// missed by `ALL` or by its name (the tests check the list is in numeric order without gaps
/// and its names are unique).
macro_rules! status_codes {
    (
        $(#[$enum_meta:meta])*
        pub enum $enum:ident {
            $( $(#[$meta:meta])* $variant:ident = $code:literal, $name:literal; )+
        }
    ) => {
        $(#[$enum_meta])*
        #[repr(u32)]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum $enum {
            $( $(#[$meta])* $variant = $code, )+
        }

        impl $enum {
            /// Every code, in numeric order.
            pub const ALL: [$enum; [$($code),+].len()] = [$($enum::$variant),+];

            /// A stable snake_case identifier (for logs and CSV output).
            pub const fn as_str(self) -> &'static str {
                match self {
                    $( $enum::$variant => $name, )+
                }
            }

            /// The wire value.
            pub const fn as_u32(self) -> u32 {
                self as u32
            }

            /// The code of a wire value; `None` for a value this build does not know.
            pub const fn from_u32(value: u32) -> Option<$enum> {
                // `ALL` is in numeric order without gaps (tested): the value is the index.
                if (value as usize) < Self::ALL.len() {
                    Some(Self::ALL[value as usize])
                } else {
                    None
                }
            }
        }

        impl core::fmt::Display for $enum {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl From<$enum> for u32 {
            fn from(code: $enum) -> u32 {
                code as u32
            }
        }
    };
}
pub(crate) use status_codes;

status_codes! {
    /// Outcome of one estimator cycle, as carried on the wire (`u32`).
    ///
    /// The numeric values are part of the schema: they never change and a retired code is never
    /// reused. A new code may be added within the same schema version (`SCHEMA_VERSION` of `cablevib-ipc`);
    /// a receiver that does not know a code ([`StatusCode::from_u32`] returns `None`) must treat
    /// the sample as "not valid".
    pub enum StatusCode {
        /// Valid estimate: tensions, f1 and stiffness are those of the echoed pose.
        Ok = 0, "ok";
        /// No tension distribution satisfies T_min ≤ T ≤ T_max and the wrench balance.
        TensionInfeasible = 1, "tension_infeasible";
        /// The input has a non-finite (NaN/Inf) component or is otherwise malformed, e.g. an
        /// orientation other than the identity (vector part over 1e-3 of the quaternion's norm)
        /// on a point-mass end-effector, which has none.
        InvalidInput = 2, "invalid_input";
        /// An iterative solver (tension or eigen) stopped at its iteration limit.
        NotConverged = 3, "not_converged";
        /// The structure or stiffness matrix is rank deficient at this pose.
        RankDeficient = 4, "rank_deficient";
        /// The position is at an anchor (a cable shorter than 1e-6 m). A position the robot
        /// cannot hold is `TensionInfeasible`: there is no geometric pre-test of the workspace.
        OutsideWorkspace = 5, "outside_workspace";
        /// No pose has been received yet (margin queries before the first estimate).
        NoPoseYet = 6, "no_pose_yet";
        /// The orientation quaternion is not of unit norm.
        NonUnitQuaternion = 7, "non_unit_quaternion";
        /// A T_min set-point below zero, above T_max or non-finite; the previous one stays in force.
        TminOutOfRange = 8, "t_min_out_of_range";
        /// A margin request with a required frequency outside `REQUIRED_F1_MIN_HZ`,
        /// `REQUIRED_F1_MAX_HZ` of `cablevib-ipc` (NaN included).
        InvalidRequest = 9, "invalid_request";
        /// An internal error of the service; see its log.
        InternalError = 10, "internal_error";
        /// A sagging cable would go slack: its end tension is below the least any catenary
        /// through its chord can have (its tension would reach zero along it). No numbers.
        CableSlack = 11, "cable_slack";
        /// A direction of the end-effector has no stiffness at this pose (a mechanism, e.g. the
        /// spin of a platform whose attachments lie on one axis): no natural frequency exists.
        /// The tensions are valid; f1 and the stiffness are NaN.
        Mechanism = 12, "mechanism";
    }
}

impl StatusCode {
    /// `true` only for [`StatusCode::Ok`].
    pub const fn is_ok(self) -> bool {
        matches!(self, StatusCode::Ok)
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
            assert_eq!(u32::from(*code), code.as_u32());
            // The name round-trips too: it names this code and no other.
            let by_name: Vec<_> = StatusCode::ALL
                .iter()
                .filter(|c| c.as_str() == code.as_str())
                .collect();
            assert_eq!(by_name, [code]);
            assert_eq!(status_str(code.as_u32()).to_string(), code.as_str());
            assert_eq!(code.to_string(), code.as_str());
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
        assert_eq!(StatusCode::NonUnitQuaternion as u32, 7);
        assert_eq!(StatusCode::TminOutOfRange as u32, 8);
        assert_eq!(StatusCode::InvalidRequest as u32, 9);
        assert_eq!(StatusCode::InternalError as u32, 10);
        assert_eq!(StatusCode::CableSlack as u32, 11);
        assert_eq!(StatusCode::Mechanism as u32, 12);
        assert_eq!(StatusCode::ALL.len(), 13);
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
