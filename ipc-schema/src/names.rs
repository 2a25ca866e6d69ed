//! iceoryx2 service names.

/// Publish-subscribe service of [`PoseSample`](crate::PoseSample)s (controller → cablevib).
pub const SERVICE_POSE: &str = "cablevib/pose";
/// Publish-subscribe service of [`TminSetpoint`](crate::TminSetpoint)s (controller → cablevib).
pub const SERVICE_T_MIN: &str = "cablevib/t_min";
/// Publish-subscribe service of [`EstimateSample`](crate::EstimateSample)s (cablevib → controller).
pub const SERVICE_ESTIMATE: &str = "cablevib/estimate";
/// Publish-subscribe service of [`VibrationSample`](crate::VibrationSample)s (a sensor on
/// the platform → cablevib), optional.
pub const SERVICE_VIBRATION: &str = "cablevib/vibration";
/// Request-response service: [`MarginRequest`](crate::MarginRequest) →
/// [`MarginResponse`](crate::MarginResponse).
pub const SERVICE_MARGIN: &str = "cablevib/margin";

/// Event service that wakes a cablevib service running with `--wait event`: a peer notifies it
/// after sending a pose ([`EVENT_ID_POSE`]), a T_min set-point ([`EVENT_ID_T_MIN`]) or a margin
/// request ([`EVENT_ID_MARGIN_REQUEST`]). Notifying is harmless when the service busy-polls.
pub const SERVICE_WAKE_SERVICE: &str = "cablevib/wake/service";
/// Event service cablevib notifies after publishing an estimate ([`EVENT_ID_ESTIMATE`]) and
/// after answering a margin request ([`EVENT_ID_MARGIN_RESPONSE`]): a controller waits on it
/// instead of polling.
pub const SERVICE_WAKE_CONTROLLER: &str = "cablevib/wake/controller";

/// Event id: a pose was sent on [`SERVICE_POSE`].
pub const EVENT_ID_POSE: usize = 1;
/// Event id: a T_min set-point was sent on [`SERVICE_T_MIN`].
pub const EVENT_ID_T_MIN: usize = 2;
/// Event id: a margin request was sent on [`SERVICE_MARGIN`].
pub const EVENT_ID_MARGIN_REQUEST: usize = 3;
/// Event id: an estimate was published on [`SERVICE_ESTIMATE`].
pub const EVENT_ID_ESTIMATE: usize = 4;
/// Event id: a margin response was sent on [`SERVICE_MARGIN`].
pub const EVENT_ID_MARGIN_RESPONSE: usize = 5;
/// Event id: a vibration sample was sent on [`SERVICE_VIBRATION`] (optional: the service
/// drains the vibration samples whenever it wakes).
pub const EVENT_ID_VIBRATION: usize = 6;

/// Every base service name, in the order pose, T_min, estimate, margin, vibration.
pub const ALL_SERVICES: [&str; 5] = [
    SERVICE_POSE,
    SERVICE_T_MIN,
    SERVICE_ESTIMATE,
    SERVICE_MARGIN,
    SERVICE_VIBRATION,
];

/// `base` prefixed with an instance name: `"{instance}/{base}"`, or `base` itself when
/// `instance` is empty. Several robots (or tests) then run side by side on one machine,
/// e.g. `prefixed("left_arm", SERVICE_POSE) == "left_arm/cablevib/pose"`. Leading and
/// trailing `/` of `instance` are ignored.
pub fn prefixed(instance: &str, base: &str) -> String {
    let instance = instance.trim_matches('/');
    if instance.is_empty() {
        base.to_owned()
    } else {
        format!("{instance}/{base}")
    }
}

/// The longest instance name, bytes (the longest service name it makes stays far below
/// iceoryx2's 255).
pub const MAX_INSTANCE_LEN: usize = 64;

/// The characters an instance name may contain, for messages.
pub const INSTANCE_CHARACTERS: &str = "ASCII letters, digits, '_', '-', '.' and '/'";

/// An instance name [`check_instance`] refuses.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "instance name {instance}: only {INSTANCE_CHARACTERS} are allowed, at most {MAX_INSTANCE_LEN} bytes"
)]
pub struct InstanceError {
    /// The name as given (quoted and escaped, cut to its first characters).
    pub instance: String,
}

/// Checks instance name `instance` (before [`prefixed`]): at most [`MAX_INSTANCE_LEN`] bytes
/// of [`INSTANCE_CHARACTERS`] (`""`, and only `/`, are the bare names). Other characters
/// (`é`, spaces, `:`) are refused here with one line naming the allowed ones, instead of
/// iceoryx2's bare "InvalidContent" when the service is opened.
pub fn check_instance(instance: &str) -> Result<(), InstanceError> {
    let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/');
    if instance.len() > MAX_INSTANCE_LEN || !instance.chars().all(allowed) {
        let mut shown: String = instance.chars().take(MAX_INSTANCE_LEN).collect();
        if shown.len() < instance.len() {
            shown.push('…');
        }
        return Err(InstanceError {
            instance: format!("{shown:?}"),
        });
    }
    Ok(())
}

/// The service names of one cablevib instance.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ServiceNames {
    /// [`SERVICE_POSE`], prefixed.
    pub pose: String,
    /// [`SERVICE_T_MIN`], prefixed.
    pub t_min: String,
    /// [`SERVICE_ESTIMATE`], prefixed.
    pub estimate: String,
    /// [`SERVICE_MARGIN`], prefixed.
    pub margin: String,
    /// [`SERVICE_VIBRATION`], prefixed.
    pub vibration: String,
    /// [`SERVICE_WAKE_SERVICE`] (event), prefixed.
    pub wake_service: String,
    /// [`SERVICE_WAKE_CONTROLLER`] (event), prefixed.
    pub wake_controller: String,
}

impl ServiceNames {
    /// The names of instance `instance` (see [`prefixed`]; `""` gives the bare names).
    pub fn new(instance: &str) -> ServiceNames {
        ServiceNames {
            pose: prefixed(instance, SERVICE_POSE),
            t_min: prefixed(instance, SERVICE_T_MIN),
            estimate: prefixed(instance, SERVICE_ESTIMATE),
            margin: prefixed(instance, SERVICE_MARGIN),
            vibration: prefixed(instance, SERVICE_VIBRATION),
            wake_service: prefixed(instance, SERVICE_WAKE_SERVICE),
            wake_controller: prefixed(instance, SERVICE_WAKE_CONTROLLER),
        }
    }

    /// The names in the order pose, T_min, estimate, margin, vibration.
    pub fn all(&self) -> [&str; 5] {
        [
            &self.pose,
            &self.t_min,
            &self.estimate,
            &self.margin,
            &self.vibration,
        ]
    }

    /// The event service names, in the order wake-service, wake-controller.
    pub fn events(&self) -> [&str; 2] {
        [&self.wake_service, &self.wake_controller]
    }
}

impl Default for ServiceNames {
    /// The bare names (no instance prefix).
    fn default() -> ServiceNames {
        ServiceNames::new("")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instance_names_are_checked_with_a_message_naming_the_allowed_characters() {
        for ok in [
            "",
            "/",
            "robot1",
            "lab/left_arm-2.0",
            &"a".repeat(MAX_INSTANCE_LEN),
        ] {
            assert!(check_instance(ok).is_ok(), "{ok}");
        }
        for bad in [
            "é/ü",
            "a b",
            "x:y",
            "\0",
            "iox2://x",
            &"a".repeat(MAX_INSTANCE_LEN + 1),
        ] {
            let e = check_instance(bad).unwrap_err().to_string();
            assert!(
                e.contains(INSTANCE_CHARACTERS) && !e.contains('\n'),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn prefixing() {
        assert_eq!(prefixed("", SERVICE_POSE), "cablevib/pose");
        assert_eq!(prefixed("robot1", SERVICE_POSE), "robot1/cablevib/pose");
        assert_eq!(
            prefixed("/robot1/", SERVICE_MARGIN),
            "robot1/cablevib/margin"
        );
        let names = ServiceNames::new("r");
        assert_eq!(
            names.all(),
            [
                "r/cablevib/pose",
                "r/cablevib/t_min",
                "r/cablevib/estimate",
                "r/cablevib/margin",
                "r/cablevib/vibration"
            ]
        );
        assert_eq!(ServiceNames::default().all(), ALL_SERVICES);
    }

    #[test]
    fn names_are_valid_iceoryx2_service_names() {
        let names = ServiceNames::new("some_instance");
        assert_eq!(
            names.events(),
            [
                "some_instance/cablevib/wake/service",
                "some_instance/cablevib/wake/controller"
            ]
        );
        for name in names.all().into_iter().chain(names.events()) {
            iceoryx2::prelude::ServiceName::new(name).expect("valid service name");
        }
    }
}
