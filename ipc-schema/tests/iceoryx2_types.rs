//! The message types through real iceoryx2 services: versioned type names, a matching
//! publisher/subscriber (and client/server) pair connects and transfers a message bit-exactly,
//! and a peer with another payload type, another layout under the same name, or the same
//! layout under another schema version is refused at open time with a clear error.
//!
//! Every test uses its own node and service names (process id, test name, clock), so the tests
//! run in parallel and alongside other processes.

use core::fmt::Debug;

use cablevib_ipc::layout::ALL_LAYOUTS;
use cablevib_ipc::{
    explain_publish_subscribe_mismatch, explain_request_response_mismatch, monotonic_now_ns,
    prefixed, EstimateSample, MarginRequest, MarginResponse, Message, PoseSample, StatusCode,
    TminSetpoint, IDENTITY_QUATERNION, MAX_CABLES, SCHEMA_VERSION,
};
use iceoryx2::prelude::*;
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use iceoryx2::service::builder::request_response::{
    RequestResponseOpenError, RequestResponseOpenOrCreateError,
};

type TestResult = Result<(), Box<dyn core::error::Error>>;

/// A service name no other test or process uses.
fn unique_name(test: &str, base: &str) -> String {
    let instance = format!(
        "cablevib_ipc_test/{}/{test}/{}",
        std::process::id(),
        monotonic_now_ns()
    );
    prefixed(&instance, base)
}

fn node() -> Node<ipc::Service> {
    NodeBuilder::new()
        .create::<ipc::Service>()
        .expect("create an iceoryx2 node")
}

fn type_name_of<T: ZeroCopySend>() -> &'static str {
    // SAFETY: reading the name has no precondition; the trait marks it unsafe because an
    // implementor promises a layout with it.
    unsafe { <T as ZeroCopySend>::type_name() }
}

fn check_type_name<M: Message>(rust_name: &str) {
    let name = type_name_of::<M>();
    assert_eq!(
        name,
        M::TYPE_NAME,
        "#[type_name] and Message::TYPE_NAME of {rust_name}"
    );
    assert_eq!(name, format!("cablevib::{rust_name}::v{SCHEMA_VERSION}"));
    let layout = ALL_LAYOUTS
        .iter()
        .find(|l| l.rust_name == rust_name)
        .expect("in ALL_LAYOUTS");
    assert_eq!(layout.type_name, name);
    assert_eq!(layout.size, core::mem::size_of::<M>());
}

#[test]
fn type_names_carry_the_schema_version() {
    check_type_name::<PoseSample>("PoseSample");
    check_type_name::<TminSetpoint>("TminSetpoint");
    check_type_name::<EstimateSample>("EstimateSample");
    check_type_name::<MarginRequest>("MarginRequest");
    check_type_name::<MarginResponse>("MarginResponse");
    let mut names: Vec<_> = ALL_LAYOUTS.iter().map(|l| l.type_name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), ALL_LAYOUTS.len(), "type names are unique");
}

/// Publishes `msg` on a fresh service and checks the subscriber gets it bit-exactly.
fn round_trip<M: Message>(test: &str, msg: M) -> TestResult {
    let node = node();
    let name = unique_name(test, M::SERVICE);
    let service = node
        .service_builder(&name.as_str().try_into()?)
        .publish_subscribe::<M>()
        .open_or_create()?;
    // A subscriber only sees samples sent after it connected: create it first.
    let subscriber = service.subscriber_builder().create()?;
    let publisher = service.publisher_builder().create()?;

    // A second process-side handle opening the same service with the same type connects.
    let same = node
        .service_builder(&name.as_str().try_into()?)
        .publish_subscribe::<M>()
        .open()?;
    let _second_subscriber = same.subscriber_builder().create()?;

    let sample = publisher.loan_uninit()?;
    sample.write_payload(msg).send()?;
    let got = subscriber.receive()?.expect("a sample");
    let got: M = *got;
    assert_eq!(as_bytes(&got), as_bytes(&msg), "bit-exact transfer");
    assert!(subscriber.receive()?.is_none());
    Ok(())
}

fn as_bytes<M: Copy>(m: &M) -> &[u8] {
    // SAFETY: the message types are repr(C) without padding (asserted in `layout`), so every
    // byte is initialised.
    unsafe { core::slice::from_raw_parts((m as *const M).cast::<u8>(), core::mem::size_of::<M>()) }
}

#[test]
fn matching_publisher_and_subscriber_connect() -> TestResult {
    let pose = PoseSample::new(7, monotonic_now_ns(), [0.1, -0.2, 0.3], IDENTITY_QUATERNION);
    round_trip("pose", pose)?;

    let t_min = TminSetpoint::per_cable(3, monotonic_now_ns(), 50.0, &[10.0, 20.0, 30.0])?;
    round_trip("t_min", t_min)?;

    let mut estimate = EstimateSample {
        pose_sequence: pose.sequence,
        pose_timestamp_ns: pose.timestamp_ns,
        status: StatusCode::Ok.into(),
        ..EstimateSample::default()
    };
    estimate.set_tensions(&[1.5; MAX_CABLES])?;
    estimate.set_stiffness(6, &[2.5; 36])?;
    estimate.f1_hz = 12.25;
    estimate.skipped_poses = u64::MAX;
    estimate.sequence = u64::MAX - 1;
    round_trip("estimate", estimate)?;
    assert!(estimate.answers(&pose));
    Ok(())
}

fn open_as<M: Message>(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<(), PublishSubscribeOpenOrCreateError> {
    node.service_builder(&name.try_into().expect("valid name"))
        .publish_subscribe::<M>()
        .open_or_create()
        .map(|_| ())
}

const INCOMPATIBLE: PublishSubscribeOpenOrCreateError =
    PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(
        PublishSubscribeOpenError::IncompatibleTypes,
    );

#[test]
fn other_payload_type_is_refused_with_a_clear_error() -> TestResult {
    let node = node();
    let name = unique_name("mismatch", cablevib_ipc::SERVICE_POSE);
    let _service = node
        .service_builder(&name.as_str().try_into()?)
        .publish_subscribe::<PoseSample>()
        .open_or_create()?;

    let err = open_as::<TminSetpoint>(&node, &name).expect_err("another payload type");
    assert_eq!(err, INCOMPATIBLE);
    // `open` (no create) reports the same, without the wrapper.
    let err = node
        .service_builder(&name.as_str().try_into()?)
        .publish_subscribe::<EstimateSample>()
        .open()
        .expect_err("another payload type");
    assert_eq!(err, PublishSubscribeOpenError::IncompatibleTypes);
    assert!(err.to_string().contains("IncompatibleTypes"), "{err}");

    // The crate's explanation names both sides.
    let text = explain_publish_subscribe_mismatch::<ipc::Service, TminSetpoint>(&name);
    assert!(
        text.contains("`cablevib::PoseSample::v4` (80 bytes, align 8)"),
        "{text}"
    );
    assert!(
        text.contains("`cablevib::TminSetpoint::v4` (160 bytes, align 8)"),
        "{text}"
    );
    assert!(text.contains(&name), "{text}");
    Ok(())
}

/// Same type name as the real pose, but one more field: a peer built against a changed layout
/// that forgot to bump the version.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, ZeroCopySend)]
#[type_name("cablevib::PoseSample::v4")]
struct PoseWithExtraField {
    sequence: u64,
    timestamp_ns: u64,
    position_m: [f64; 3],
    orientation_wxyz: [f64; 4],
    flags: u32,
    reserved0: u32,
    velocity: [f64; 3],
}

/// Same layout as the real pose under the next schema version's name.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, ZeroCopySend)]
#[type_name("cablevib::PoseSample::v5")]
struct PoseNextVersion {
    sequence: u64,
    timestamp_ns: u64,
    position_m: [f64; 3],
    orientation_wxyz: [f64; 4],
    flags: u32,
    reserved0: u32,
}

fn open_raw<T: Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
) -> Result<(), PublishSubscribeOpenOrCreateError> {
    node.service_builder(&name.try_into().expect("valid name"))
        .publish_subscribe::<T>()
        .open_or_create()
        .map(|_| ())
}

#[test]
fn other_layout_or_version_under_the_same_name_is_refused() -> TestResult {
    assert_eq!(
        core::mem::size_of::<PoseNextVersion>(),
        core::mem::size_of::<PoseSample>()
    );
    let node = node();
    let name = unique_name("layout", cablevib_ipc::SERVICE_POSE);
    let _service = node
        .service_builder(&name.as_str().try_into()?)
        .publish_subscribe::<PoseSample>()
        .open_or_create()?;
    assert_eq!(
        open_raw::<PoseWithExtraField>(&node, &name),
        Err(INCOMPATIBLE)
    );
    assert_eq!(open_raw::<PoseNextVersion>(&node, &name), Err(INCOMPATIBLE));
    // And the right type still opens.
    assert_eq!(open_as::<PoseSample>(&node, &name), Ok(()));
    Ok(())
}

#[test]
fn margin_request_response_round_trip_and_mismatch() -> TestResult {
    let node = node();
    let name = unique_name("margin", cablevib_ipc::SERVICE_MARGIN);
    let service = node
        .service_builder(&name.as_str().try_into()?)
        .request_response::<MarginRequest, MarginResponse>()
        .open_or_create()?;
    let server = service.server_builder().create()?;
    let client = service.client_builder().create()?;

    let request = MarginRequest::new(11, monotonic_now_ns(), 8.0);
    let pending = client.send_copy(request)?;
    let active = server.receive()?.expect("a request");
    assert_eq!(*active, request);
    let response = MarginResponse::from_f1(
        &active,
        5,
        StatusCode::Ok,
        10.0,
        f64::NAN,
        monotonic_now_ns(),
    );
    active.send_copy(response)?;
    let got = pending.receive()?.expect("a response");
    assert_eq!(as_bytes(&*got), as_bytes(&response));
    assert_eq!(
        (got.request_sequence, got.margin_hz, got.margin_ratio),
        (11, 2.0, 1.25)
    );

    // Request and response swapped: refused.
    let err = node
        .service_builder(&name.as_str().try_into()?)
        .request_response::<MarginResponse, MarginRequest>()
        .open_or_create()
        .map(|_| ())
        .expect_err("swapped types");
    assert_eq!(
        err,
        RequestResponseOpenOrCreateError::RequestResponseOpenError(
            RequestResponseOpenError::IncompatibleRequestOrResponseType
        )
    );
    let text =
        explain_request_response_mismatch::<ipc::Service, MarginResponse, MarginRequest>(&name);
    assert!(
        text.contains("carries request `cablevib::MarginRequest::v4` (24 bytes, align 8) and response `cablevib::MarginResponse::v4` (64 bytes, align 8)"),
        "{text}"
    );
    Ok(())
}

#[test]
fn explanation_of_a_missing_service_is_still_readable() {
    let name = unique_name("missing", cablevib_ipc::SERVICE_ESTIMATE);
    let text = explain_publish_subscribe_mismatch::<ipc::Service, EstimateSample>(&name);
    assert!(text.contains("could not be read"), "{text}");
    assert!(text.contains("cablevib::EstimateSample::v4"), "{text}");
}
