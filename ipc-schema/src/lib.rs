//! Zero-copy iceoryx2 message types of the cablevib service.
//!
//! A cablevib service process subscribes to the end-effector pose and to minimum-tension
//! set-points, runs the real-time estimator on each new pose (tension distribution, cable
//! stiffness, first natural frequency) and publishes an estimate; a co-located controller reads
//! the estimates or asks for its vibration margin. This crate is the contract between them:
//! message types, service names, status codes and the schema version. It has no estimator
//! code, so a controller depends on it alone.
//!
//! | service ([`names`])   | pattern          | payload                                     | direction            |
//! |-----------------------|------------------|---------------------------------------------|----------------------|
//! | [`SERVICE_POSE`]      | publish-subscribe| [`PoseSample`]                              | controller → cablevib |
//! | [`SERVICE_T_MIN`]     | publish-subscribe| [`TminSetpoint`]                            | controller → cablevib |
//! | [`SERVICE_ESTIMATE`]  | publish-subscribe| [`EstimateSample`]                          | cablevib → controller |
//! | [`SERVICE_MARGIN`]    | request-response | [`MarginRequest`] → [`MarginResponse`]      | controller ⇄ cablevib |
//! | [`SERVICE_VIBRATION`] | publish-subscribe| [`VibrationSample`] (optional)              | sensor → cablevib     |
//!
//! Several instances share a machine by prefixing the names ([`prefixed`], [`ServiceNames`]).
//!
//! Two event services carry wake-ups, for peers that block instead of busy-polling: a peer
//! notifies [`SERVICE_WAKE_SERVICE`] after sending a pose, set-point or margin request, and
//! cablevib notifies [`SERVICE_WAKE_CONTROLLER`] after each estimate and margin response (event
//! ids `EVENT_ID_*`). The data always travels on the services above; an event only says "look".
//!
//! # Layout
//!
//! Every message is `#[repr(C)]`, `Copy` and of fixed size: per-cable arrays hold
//! [`MAX_CABLES`] entries with a count of the valid ones, the stiffness matrix holds
//! [`MAX_STIFFNESS_DIM`]² entries. There is no implicit padding (padding is an explicit
//! `reserved*` field that senders set to 0), and sizes, alignments and offsets are asserted at
//! compile time ([`layout`]). `include/cablevib_ipc.h` declares the same structs for C and C++
//! controllers (with `IOX2_TYPE_NAME` for iceoryx2-cxx); a test compiles it and compares every
//! offset with the Rust layout.
//!
//! # Units
//!
//! SI throughout, with the unit in the field name: positions in m (`_m`), forces and tensions
//! in N (`_n`), frequencies in Hz (`_hz`, not rad/s), times in ns (`_ns`). Orientation is a
//! unit quaternion `[w, x, y, z]`, identity `[1, 0, 0, 0]` ([`IDENTITY_QUATERNION`]).
//! Stiffness is row-major: N/m for translations, N·m/rad for rotations, N/rad for coupling
//! terms.
//!
//! # Sequence numbers and timestamps
//!
//! Every message carries its sender's sequence number (incremented by one per message, so a
//! gap means a lost or skipped message) and the sender's timestamp: `CLOCK_MONOTONIC` in ns
//! ([`monotonic_now_ns`]), which all processes on one machine share, so differences of
//! timestamps from different processes are latencies.
//!
//! An [`EstimateSample`] has no sequence of its own: it echoes the `sequence` and
//! `timestamp_ns` of the pose it answers (`pose_sequence`, `pose_timestamp_ns`), next to the
//! service's receive and publish times. A controller compares `pose_sequence` with the pose it
//! last sent ([`EstimateSample::answers`]) to tell a fresh estimate from a stale one, and
//! `now − pose_timestamp_ns` is the end-to-end latency. Likewise a [`MarginResponse`] echoes
//! the request's sequence and names the pose its answer is based on. The numeric values of an
//! estimate or a margin response mean something only when `status` is [`StatusCode::Ok`];
//! otherwise frequencies are NaN. [`Default`] of those two types is the safe "no estimate"
//! value; `zeroed()` is all bits zero (and so reads as status Ok).
//!
//! # Versioning
//!
//! Every iceoryx2 type name ends with `::v{SCHEMA_VERSION}` (e.g.
//! `cablevib::PoseSample::v4`, [`Message::TYPE_NAME`]). iceoryx2 compares the type name, size
//! and alignment of the payload when a port opens a service, so a peer built against another
//! schema is refused at connect time (`IncompatibleTypes`; [`compat`] turns that into a
//! readable message) instead of misreading bytes. The rule: **any change of a message's
//! layout or of the meaning of a field bumps [`SCHEMA_VERSION`] and the suffix of every type
//! name** (the tests check they agree), and the C header with it. Adding a [`StatusCode`]
//! does not: a receiver treats an unknown code as "not valid". Status values and service
//! names never change meaning.
//!
//! # Example
//!
//! ```no_run
//! use cablevib_ipc::{monotonic_now_ns, PoseSample, ServiceNames, IDENTITY_QUATERNION};
//! use iceoryx2::prelude::*;
//!
//! # fn main() -> Result<(), Box<dyn core::error::Error>> {
//! let names = ServiceNames::default();
//! let node = NodeBuilder::new().create::<ipc::Service>()?;
//! let service = node
//!     .service_builder(&names.pose.as_str().try_into()?)
//!     .publish_subscribe::<PoseSample>()
//!     .open_or_create()?;
//! let publisher = service.publisher_builder().create()?;
//! let pose = PoseSample::new(1, monotonic_now_ns(), [0.1, 0.0, 0.5], IDENTITY_QUATERNION);
//! publisher.send_copy(pose)?;
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

pub mod attributes;
pub mod compat;
pub mod layout;
pub mod messages;
pub mod names;
/// The status codes are the core's (`cablevib::status`): one definition for the estimator
/// and the wire.
pub use cablevib::status;

pub use attributes::{
    schema_version_value, ALL_ATTRIBUTE_KEYS, ATTR_CABLEVIB_VERSION, ATTR_ELEMENTS_PER_CABLE,
    ATTR_ELEMENT_MODEL, ATTR_SCENE, ATTR_SCHEMA_VERSION, ATTR_UNITS, UNITS,
};
/// The measured-frequency status codes are the core's (`cablevib::measured`): one definition
/// for the tracker and the wire.
pub use cablevib::measured::MeasuredStatus;
pub use compat::{explain_publish_subscribe_mismatch, explain_request_response_mismatch, TypeInfo};
pub use messages::{
    EstimateSample, MarginRequest, MarginResponse, Message, PoseSample, SchemaError, TminSetpoint,
    VibrationSample, EE_MODE_AGE_UNKNOWN, IDENTITY_QUATERNION, MEASURED_AGE_UNKNOWN,
    REQUIRED_F1_MAX_HZ, REQUIRED_F1_MIN_HZ, T_MIN_AGE_UNKNOWN, VIBRATION_FLAG_ANGULAR_VELOCITY,
};
pub use names::{
    check_instance, prefixed, InstanceError, ServiceNames, ALL_SERVICES, EVENT_ID_ESTIMATE,
    EVENT_ID_MARGIN_REQUEST, EVENT_ID_MARGIN_RESPONSE, EVENT_ID_POSE, EVENT_ID_T_MIN,
    EVENT_ID_VIBRATION, INSTANCE_CHARACTERS, MAX_INSTANCE_LEN, SERVICE_ESTIMATE, SERVICE_MARGIN,
    SERVICE_POSE, SERVICE_T_MIN, SERVICE_VIBRATION, SERVICE_WAKE_CONTROLLER, SERVICE_WAKE_SERVICE,
};
pub use status::{status_str, StatusCode, StatusText};

/// Largest number of cables a message can describe (length of the per-cable arrays): the
/// core's limit on a scene.
pub use cablevib::scene::MAX_CABLES;

/// Largest end-effector stiffness dimension (6: three translations, three rotations).
pub const MAX_STIFFNESS_DIM: usize = 6;

/// Version of the wire schema; every type name ends with `::v{SCHEMA_VERSION}`.
pub const SCHEMA_VERSION: u32 = 4;

/// `CLOCK_MONOTONIC` now, ns: the clock of every `*timestamp_ns` field. It is shared by all
/// processes of a machine (it counts from boot), never jumps, and takes ~20 ns (vDSO, no
/// system call).
#[cfg(unix)]
pub fn monotonic_now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; CLOCK_MONOTONIC is always supported on
    // Linux and the BSDs, so the call cannot fail.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    debug_assert_eq!(rc, 0, "clock_gettime(CLOCK_MONOTONIC) failed");
    (ts.tv_sec as u64) * 1_000_000_000 + ts.tv_nsec as u64
}

/// Monotonic time, ns, since the first call in this process (non-Unix fallback: not
/// comparable across processes).
#[cfg(not(unix))]
pub fn monotonic_now_ns() -> u64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_nanos() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotonic_clock_advances_like_instant() {
        let (t0, i0) = (monotonic_now_ns(), std::time::Instant::now());
        std::thread::sleep(std::time::Duration::from_millis(2));
        let (t1, i1) = (monotonic_now_ns(), std::time::Instant::now());
        let dt = (t1 - t0) as i128;
        let di = (i1 - i0).as_nanos() as i128;
        assert!(dt >= 2_000_000, "{dt}");
        assert!(
            (dt - di).abs() < 1_000_000,
            "clock {dt} ns vs Instant {di} ns"
        );
    }
}
