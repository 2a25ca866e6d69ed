//! `[damping]`: which kind of structural damping, and its values within their bounds.

use super::Checker;
use crate::input_file::message_number;
use crate::scene::parse::RawDamping;
use crate::scene::{Damping, SceneError};

/// `[damping]`: at most one kind; each value finite, ≥ 0 and below its bound (ζ < 1 and
/// η < 2: critical damping is not a structure's; Rayleigh α, β bounded against unit slips).
pub(super) fn validate_damping(
    ck: &Checker,
    raw: Option<RawDamping>,
) -> Result<Damping, SceneError> {
    let Some(d) = raw else {
        return Ok(Damping::None);
    };
    let rayleigh = d.rayleigh_alpha.is_some() || d.rayleigh_beta.is_some();
    let kinds = [d.loss_factor.is_some(), rayleigh, d.modal_ratio.is_some()];
    match kinds.iter().filter(|&&k| k).count() {
        0 => {
            return Err(ck.inv(
                "damping",
                "an empty [damping] table: give loss_factor, rayleigh_alpha/rayleigh_beta or modal_ratio (or drop the table for no damping)".into(),
            ))
        }
        1 => {}
        _ => {
            return Err(ck.inv(
                "damping",
                "give one kind of damping: loss_factor, rayleigh_alpha/rayleigh_beta or modal_ratio, not several".into(),
            ))
        }
    }
    let bounded = |key: &str, x: f64, max: f64, what: &str| -> Result<f64, SceneError> {
        if x.is_finite() && (0.0..max).contains(&x) {
            Ok(x)
        } else {
            Err(ck.inv(
                key,
                format!(
                    "{} must be finite, ≥ 0 and < {} ({what})",
                    message_number(x),
                    message_number(max)
                ),
            ))
        }
    };
    if let Some(eta) = d.loss_factor {
        let eta = bounded(
            "damping.loss_factor",
            eta,
            crate::scene::MAX_LOSS_FACTOR,
            "η/2 = 1 is critical damping",
        )?;
        return Ok(Damping::LossFactor { eta });
    }
    if let Some(zeta) = d.modal_ratio {
        let zeta = bounded(
            "damping.modal_ratio",
            zeta,
            crate::scene::MAX_MODAL_RATIO,
            "a fraction of critical damping; 1 is critical",
        )?;
        return Ok(Damping::ModalRatio { zeta });
    }
    let alpha_per_s = bounded(
        "damping.rayleigh_alpha",
        d.rayleigh_alpha.unwrap_or(0.0),
        crate::scene::MAX_RAYLEIGH_ALPHA_PER_S,
        "1/s",
    )?;
    let beta_s = bounded(
        "damping.rayleigh_beta",
        d.rayleigh_beta.unwrap_or(0.0),
        crate::scene::MAX_RAYLEIGH_BETA_S,
        "s",
    )?;
    Ok(Damping::Rayleigh {
        alpha_per_s,
        beta_s,
    })
}
