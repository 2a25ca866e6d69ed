//! iceoryx2 service attributes: what a peer can read about a cablevib service before it talks.
//!
//! Every cablevib participant that creates one of an instance's services (publish-subscribe,
//! request-response or event) defines these key-value attributes on it; iceoryx2 stores them in
//! the service's static configuration, where any peer that may open the service reads them
//! (Rust `PortFactory::attributes`, Python `Service.details(...).attributes()`, C++
//! `attributes()`). They never change during the life of the service.
//!
//! | key | value | defined by |
//! |---|---|---|
//! | [`ATTR_SCHEMA_VERSION`] | [`SCHEMA_VERSION`](crate::SCHEMA_VERSION) in decimal, e.g. `"1"` | every cablevib participant |
//! | [`ATTR_UNITS`] | [`UNITS`] | every cablevib participant |
//! | [`ATTR_CABLEVIB_VERSION`] | the creating program's cablevib version, e.g. `"0.1.0"` | every cablevib participant |
//! | [`ATTR_SCENE`] | scene name | `cablevib serve` only |
//! | [`ATTR_ELEMENT_MODEL`] | cable element model, e.g. `"bar"` | `cablevib serve` only |
//! | [`ATTR_ELEMENTS_PER_CABLE`] | elements per cable in decimal | `cablevib serve` only |
//!
//! Whoever comes first creates a service, so the scene attributes are present when `cablevib
//! serve` started before its peers (the usual order) and absent on a service that a peer
//! created first. The schema version is always there on a service a cablevib program created;
//! a peer that finds another value was built against another schema (iceoryx2 would refuse its
//! payload type as well, by the `::v{N}` suffix of the type names).

/// Key: the wire schema version the creator was built with ([`schema_version_value`]).
pub const ATTR_SCHEMA_VERSION: &str = "cablevib.schema_version";
/// Key: the unit system of every message ([`UNITS`]).
pub const ATTR_UNITS: &str = "cablevib.units";
/// Key: the cablevib version of the program that created the service.
pub const ATTR_CABLEVIB_VERSION: &str = "cablevib.version";
/// Key: the name of the scene `cablevib serve` estimates.
pub const ATTR_SCENE: &str = "cablevib.scene";
/// Key: the cable element model of that scene.
pub const ATTR_ELEMENT_MODEL: &str = "cablevib.element_model";
/// Key: the number of elements per cable of that scene.
pub const ATTR_ELEMENTS_PER_CABLE: &str = "cablevib.elements_per_cable";

/// Value of [`ATTR_UNITS`]: SI with the unit in each field name (see the crate's Units section).
pub const UNITS: &str = "SI: N, m, Hz, s; timestamps ns";

/// Every key, in the order of the table above.
pub const ALL_ATTRIBUTE_KEYS: [&str; 6] = [
    ATTR_SCHEMA_VERSION,
    ATTR_UNITS,
    ATTR_CABLEVIB_VERSION,
    ATTR_SCENE,
    ATTR_ELEMENT_MODEL,
    ATTR_ELEMENTS_PER_CABLE,
];

/// The value of [`ATTR_SCHEMA_VERSION`] of this build: [`SCHEMA_VERSION`](crate::SCHEMA_VERSION)
/// in decimal.
pub fn schema_version_value() -> String {
    crate::SCHEMA_VERSION.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use iceoryx2::service::attribute::{AttributeKey, AttributeValue};

    #[test]
    fn keys_and_values_fit_iceoryx2() {
        for key in ALL_ATTRIBUTE_KEYS {
            AttributeKey::try_from(key).expect("valid attribute key");
        }
        AttributeValue::try_from(UNITS).expect("valid attribute value");
        assert!(
            ALL_ATTRIBUTE_KEYS.len() <= iceoryx2::constants::MAX_ATTRIBUTES,
            "iceoryx2 stores at most MAX_ATTRIBUTES attributes per service"
        );
    }
}
