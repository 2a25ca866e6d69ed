//! The iceoryx2 service attributes cablevib defines on every service it creates, and reading
//! them back. The keys and what they mean are in `cablevib_ipc::attributes`.
//!
//! Opening a service that carries a schema-version attribute other than this build's fails
//! with [`ServiceError::IncompatiblePeer`]. A service without the attribute (created by a peer
//! that defines none, e.g. a plain iceoryx2 program) is accepted: its payload type names
//! still carry the schema version and iceoryx2 compares them.

#[allow(unused_imports)]
use super::*;

use cablevib_ipc::{
    schema_version_value, ATTR_CABLEVIB_VERSION, ATTR_ELEMENTS_PER_CABLE, ATTR_ELEMENT_MODEL,
    ATTR_SCENE, ATTR_SCHEMA_VERSION, ATTR_UNITS, SCHEMA_VERSION, UNITS,
};
use iceoryx2::service::attribute::{AttributeKey, AttributeValue};

use crate::scene::Scene;

/// The attributes a cablevib program defines on a service it creates.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ServiceAttributes {
    pairs: Vec<(&'static str, String)>,
}

impl ServiceAttributes {
    /// What every cablevib participant defines: schema version, units and this build's
    /// cablevib version.
    pub fn contract() -> ServiceAttributes {
        ServiceAttributes {
            pairs: vec![
                (ATTR_SCHEMA_VERSION, schema_version_value()),
                (ATTR_UNITS, UNITS.to_owned()),
                (ATTR_CABLEVIB_VERSION, env!("CARGO_PKG_VERSION").to_owned()),
            ],
        }
    }

    /// What `cablevib serve` defines: [`ServiceAttributes::contract`] plus the scene's name,
    /// cable element model and elements per cable.
    pub fn of_scene(scene: &Scene) -> ServiceAttributes {
        let mut a = ServiceAttributes::contract();
        a.pairs.extend([
            (ATTR_SCENE, scene.name.clone()),
            (ATTR_ELEMENT_MODEL, scene.model.element.as_str().to_owned()),
            (
                ATTR_ELEMENTS_PER_CABLE,
                scene.model.elements_per_cable.to_string(),
            ),
        ]);
        a
    }

    /// The key-value pairs, in definition order.
    pub fn pairs(&self) -> &[(&'static str, String)] {
        &self.pairs
    }

    /// The iceoryx2 specifier to create a service with. Fails when a value does not fit an
    /// iceoryx2 attribute value (e.g. a scene name longer than 256 bytes).
    pub(super) fn specifier(&self) -> Result<AttributeSpecifier, ServiceError> {
        let mut spec = AttributeSpecifier::new();
        for (key, value) in &self.pairs {
            let k = AttributeKey::try_from(*key).map_err(|e| ServiceError::Name {
                what: format!("attribute key `{key}`"),
                reason: format!("{e:?}"),
            })?;
            let v = AttributeValue::try_from(value.as_str()).map_err(|e| ServiceError::Name {
                what: format!("attribute {key} = `{value}`"),
                reason: format!("{e:?}"),
            })?;
            spec = spec
                .define(&k, &v)
                .map_err(|e| ipc_error(format!("define attribute {key}"), e))?;
        }
        Ok(spec)
    }
}

/// The attributes of an existing service, as read by a peer.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadAttributes {
    /// Key-value pairs, in iceoryx2's (sorted) order.
    pub pairs: Vec<(String, String)>,
}

impl ReadAttributes {
    /// Copies the attributes of an iceoryx2 service.
    pub fn from_set(set: &AttributeSet) -> ReadAttributes {
        ReadAttributes {
            pairs: set
                .iter()
                .map(|a| (a.key().to_string(), a.value().to_string()))
                .collect(),
        }
    }

    /// The (first) value of `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.pairs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Fails with [`ServiceError::IncompatiblePeer`] when service `service` carries a schema
    /// version other than this build's, or (with `required`) none at all.
    pub fn check_schema(&self, service: &str, required: bool) -> Result<(), ServiceError> {
        match self.get(ATTR_SCHEMA_VERSION) {
            Some(v) if v == schema_version_value() => Ok(()),
            None if !required => Ok(()),
            found => Err(ServiceError::IncompatiblePeer(format!(
                "service \"{service}\" has {ATTR_SCHEMA_VERSION} = {}, but this process uses \
                 cablevib-ipc schema v{SCHEMA_VERSION}; rebuild the other peer against the same \
                 schema version, or give this instance another service-name prefix",
                found.map_or_else(|| "(none)".to_owned(), |v| format!("\"{v}\""))
            ))),
        }
    }
}

impl core::fmt::Display for ReadAttributes {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for (i, (k, v)) in self.pairs.iter().enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            write!(f, "{sep}{k}={v}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schema_check() {
        let ours = ReadAttributes {
            pairs: vec![(ATTR_SCHEMA_VERSION.into(), schema_version_value())],
        };
        assert!(ours.check_schema("s", true).is_ok());
        let none = ReadAttributes::default();
        assert!(none.check_schema("s", false).is_ok());
        assert!(matches!(
            none.check_schema("s", true),
            Err(ServiceError::IncompatiblePeer(_))
        ));
        let other = ReadAttributes {
            pairs: vec![(ATTR_SCHEMA_VERSION.into(), "999".into())],
        };
        let err = other.check_schema("s", false).unwrap_err().to_string();
        assert!(err.contains("\"999\"") && err.contains("schema v"), "{err}");
    }

    #[test]
    fn scene_attributes_fit_iceoryx2() {
        let a = ServiceAttributes::of_scene(&Scene::default_scene());
        assert_eq!(a.pairs().len(), cablevib_ipc::ALL_ATTRIBUTE_KEYS.len());
        let spec = a.specifier().expect("fits");
        let read = ReadAttributes::from_set(spec.attributes());
        assert_eq!(read.get(ATTR_SCENE), Some("spatial-paper"));
    }
}
