//! TOML parsing: the scene file as serde reads it (`Raw*` types, unknown keys rejected,
//! defaults filled in), before any physical check. Fixed-size arrays are read as any TOML
//! value ([`RawArray`]) and checked element by element in `validate`: serde's `[f64; N]`
//! would silently drop elements past the N-th, and its errors cannot name `cables[i]`.

use super::ElementKind;
use serde::Deserialize;

/// A fixed-size array of numbers as written (any TOML value): `validate` checks that it is
/// an array of exactly the expected length whose elements are numbers.
#[derive(Debug, Clone, Deserialize)]
#[serde(transparent)]
pub(super) struct RawArray(pub(super) toml::Value);

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub(super) name: String,
    pub(super) gravity: RawArray,
    pub(super) end_effector: RawEndEffector,
    pub(super) cable: RawCableDefaults,
    pub(super) tension: RawTension,
    pub(super) model: RawModel,
    #[serde(default)]
    pub(super) effects: Option<RawEffects>,
    #[serde(default)]
    pub(super) damping: Option<RawDamping>,
    pub(super) cables: Vec<RawCable>,
}

/// `[effects]`: which physics the scene asks for; nothing switched off is computed.
#[derive(Debug, Deserialize, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEffects {
    pub(super) geometric_stiffness: Option<bool>,
    pub(super) cable_mass: Option<bool>,
    pub(super) sag: Option<bool>,
    pub(super) rotation: Option<bool>,
}

/// `[damping]`: one kind at a time (checked in `validate`).
#[derive(Debug, Deserialize, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDamping {
    pub(super) loss_factor: Option<f64>,
    pub(super) rayleigh_alpha: Option<f64>,
    pub(super) rayleigh_beta: Option<f64>,
    pub(super) modal_ratio: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEndEffector {
    pub(super) mass: f64,
    pub(super) position: RawArray,
    pub(super) inertia: Option<RawArray>,
    pub(super) orientation: Option<RawArray>,
    #[serde(default = "default_true")]
    pub(super) weight_carried: bool,
}

fn default_true() -> bool {
    true
}

#[derive(Debug, Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCableDefaults {
    pub(super) youngs_modulus: Option<f64>,
    pub(super) area: Option<f64>,
    pub(super) weight_per_length: Option<f64>,
    pub(super) mass_per_length: Option<f64>,
    pub(super) pulley: Option<RawPulley>,
    /// Hidden cable (pulley entry to winch drum): length, m.
    pub(super) hidden_length: Option<f64>,
    /// Hidden cable: Young's modulus, Pa (default: the free cable's).
    pub(super) hidden_youngs_modulus: Option<f64>,
    /// Hidden cable: cross-section, m² (default: the free cable's).
    pub(super) hidden_area: Option<f64>,
    /// Hidden cable: weight per length, N/m (default: the free cable's).
    pub(super) hidden_weight_per_length: Option<f64>,
    /// Hidden cable: mass per length, kg/m (default: the free cable's).
    pub(super) hidden_mass_per_length: Option<f64>,
}

/// `[cable.pulley]` / `[cables.pulley]`: a swivel pulley at the anchor.
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPulley {
    pub(super) radius: f64,
    pub(super) entry_direction: RawArray,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTension {
    pub(super) t_min: f64,
    pub(super) t_max: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawModel {
    pub(super) element: ElementKind,
    #[serde(default = "default_elements")]
    pub(super) elements_per_cable: i64,
    #[serde(default = "default_participation")]
    pub(super) ee_participation_min: f64,
    #[serde(default = "default_f1_tolerance")]
    pub(super) f1_tolerance: f64,
}

fn default_f1_tolerance() -> f64 {
    1e-3
}

fn default_elements() -> i64 {
    10
}
fn default_participation() -> f64 {
    0.5
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCable {
    pub(super) anchor: RawArray,
    pub(super) attachment: Option<RawArray>,
    pub(super) youngs_modulus: Option<f64>,
    pub(super) area: Option<f64>,
    pub(super) weight_per_length: Option<f64>,
    pub(super) mass_per_length: Option<f64>,
    pub(super) t_min: Option<f64>,
    pub(super) t_max: Option<f64>,
    pub(super) pulley: Option<RawPulley>,
    /// Hidden cable (pulley entry to winch drum): length, m.
    pub(super) hidden_length: Option<f64>,
    /// Hidden cable: Young's modulus, Pa (default: the free cable's).
    pub(super) hidden_youngs_modulus: Option<f64>,
    /// Hidden cable: cross-section, m² (default: the free cable's).
    pub(super) hidden_area: Option<f64>,
    /// Hidden cable: weight per length, N/m (default: the free cable's).
    pub(super) hidden_weight_per_length: Option<f64>,
    /// Hidden cable: mass per length, kg/m (default: the free cable's).
    pub(super) hidden_mass_per_length: Option<f64>,
}
