//! Clear errors for a peer built against another schema.
//!
//! iceoryx2 refuses to open a service whose payload type name, size or alignment differ from
//! the caller's, but its error (`PublishSubscribeOpenError::IncompatibleTypes`,
//! `RequestResponseOpenError::IncompatibleRequestOrResponseType`) does not say what the
//! existing service carries. The functions here read that from the service's static
//! configuration and phrase it for a log line.

use iceoryx2::config::Config;
use iceoryx2::prelude::{MessagingPattern, ServiceName};
use iceoryx2::service::static_config::message_type_details::TypeDetail;
use iceoryx2::service::static_config::messaging_pattern::MessagingPattern as PatternConfig;
use iceoryx2::service::Service;

use crate::messages::Message;
use crate::SCHEMA_VERSION;

/// A payload type as iceoryx2 compares it at connect time: name, size and alignment.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TypeInfo {
    /// iceoryx2 type name.
    pub type_name: String,
    /// Size, bytes.
    pub size: usize,
    /// Alignment, bytes.
    pub alignment: usize,
}

impl TypeInfo {
    /// The type info of message `M` in this build.
    pub fn of<M: Message>() -> TypeInfo {
        TypeInfo {
            type_name: M::TYPE_NAME.to_owned(),
            size: core::mem::size_of::<M>(),
            alignment: core::mem::align_of::<M>(),
        }
    }

    fn from_detail(d: &TypeDetail) -> TypeInfo {
        TypeInfo {
            type_name: d.type_name().to_string(),
            size: d.size(),
            alignment: d.alignment(),
        }
    }
}

impl core::fmt::Display for TypeInfo {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "`{}` ({} bytes, align {})",
            self.type_name, self.size, self.alignment
        )
    }
}

/// The payload type of the existing publish-subscribe service `service_name`, or `None` when
/// there is no such service or its configuration cannot be read.
pub fn existing_publish_subscribe_payload<S: Service>(service_name: &str) -> Option<TypeInfo> {
    let name = ServiceName::new(service_name).ok()?;
    let details = S::details(
        &name,
        Config::global_config(),
        MessagingPattern::PublishSubscribe,
    )
    .ok()??;
    match details.static_details.messaging_pattern() {
        PatternConfig::PublishSubscribe(c) => {
            Some(TypeInfo::from_detail(&c.message_type_details().payload))
        }
        _ => None,
    }
}

/// The (request, response) payload types of the existing request-response service
/// `service_name`, or `None` when there is no such service or it cannot be read.
pub fn existing_request_response_payloads<S: Service>(
    service_name: &str,
) -> Option<(TypeInfo, TypeInfo)> {
    let name = ServiceName::new(service_name).ok()?;
    let details = S::details(
        &name,
        Config::global_config(),
        MessagingPattern::RequestResponse,
    )
    .ok()??;
    match details.static_details.messaging_pattern() {
        PatternConfig::RequestResponse(c) => Some((
            TypeInfo::from_detail(&c.request_message_type_details().payload),
            TypeInfo::from_detail(&c.response_message_type_details().payload),
        )),
        _ => None,
    }
}

fn rebuild_hint() -> String {
    format!(
        "this process uses cablevib-ipc schema v{SCHEMA_VERSION}; rebuild the other peer \
         against the same schema version, or give this instance another service-name prefix"
    )
}

/// A log-ready explanation of why opening publish-subscribe service `service_name` with
/// payload `M` failed with an incompatible-types error: what the service carries versus
/// what this process expects.
pub fn explain_publish_subscribe_mismatch<S: Service, M: Message>(service_name: &str) -> String {
    let ours = TypeInfo::of::<M>();
    match existing_publish_subscribe_payload::<S>(service_name) {
        Some(theirs) => format!(
            "service \"{service_name}\" carries payload {theirs}, but this process expects \
             {ours}; {}",
            rebuild_hint()
        ),
        None => format!(
            "service \"{service_name}\" exists with an incompatible payload type (its details \
             could not be read); this process expects {ours}; {}",
            rebuild_hint()
        ),
    }
}

/// A log-ready explanation of why opening request-response service `service_name` with
/// request `Req` and response `Resp` failed with an incompatible-types error.
pub fn explain_request_response_mismatch<S: Service, Req: Message, Resp: Message>(
    service_name: &str,
) -> String {
    let (req, resp) = (TypeInfo::of::<Req>(), TypeInfo::of::<Resp>());
    match existing_request_response_payloads::<S>(service_name) {
        Some((their_req, their_resp)) => format!(
            "service \"{service_name}\" carries request {their_req} and response {their_resp}, \
             but this process expects request {req} and response {resp}; {}",
            rebuild_hint()
        ),
        None => format!(
            "service \"{service_name}\" exists with incompatible request/response types (its \
             details could not be read); this process expects request {req} and response \
             {resp}; {}",
            rebuild_hint()
        ),
    }
}
