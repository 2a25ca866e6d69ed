//! The hidden cable's keys (`hidden_length`, `hidden_youngs_modulus`, `hidden_area`,
//! `hidden_weight_per_length`, `hidden_mass_per_length`) of one cable: each from the cable's
//! own table, else from `[cable]`; the material defaults to the free cable's.

use super::{cable_key, validate_axial_rigidity, weight_or_mass_per_length, Checker};
use crate::scene::parse::{RawCable, RawCableDefaults};
use crate::scene::{HiddenCable, SceneError};

/// Cable `i`'s hidden part, or None when no `hidden_length` is given (or it is 0). `free`:
/// the free cable's (E Pa, A m², μ kg/m); `g`: |g|, m/s² (weight → mass per length).
pub(super) fn validate_hidden(
    ck: &Checker,
    i: usize,
    c: &RawCable,
    d: &RawCableDefaults,
    free: (f64, f64, f64),
    g: f64,
) -> Result<Option<HiddenCable>, SceneError> {
    let key = |k: &str| cable_key(i, k);
    let length = c.hidden_length.or(d.hidden_length);
    let e = c.hidden_youngs_modulus.or(d.hidden_youngs_modulus);
    let a = c.hidden_area.or(d.hidden_area);
    let (w, m) = if c.hidden_weight_per_length.is_some() || c.hidden_mass_per_length.is_some() {
        (c.hidden_weight_per_length, c.hidden_mass_per_length)
    } else {
        (d.hidden_weight_per_length, d.hidden_mass_per_length)
    };
    let length = match length {
        None => {
            if e.is_some() || a.is_some() || w.is_some() || m.is_some() {
                return Err(ck.inv(
                    &key("hidden_length"),
                    "missing: the hidden cable's material is given without its length".into(),
                ));
            }
            return Ok(None);
        }
        Some(0.0) => return Ok(None),
        Some(l) => ck.positive(&key("hidden_length"), l)?,
    };
    let e = match e {
        Some(e) => ck.positive(&key("hidden_youngs_modulus"), e)?,
        None => free.0,
    };
    let a = match a {
        Some(a) => ck.positive(&key("hidden_area"), a)?,
        None => free.1,
    };
    let mu = weight_or_mass_per_length(ck, i, "hidden_", w, m, g)?.unwrap_or(free.2);
    validate_axial_rigidity(ck, i, e * a).map_err(|_| {
        ck.inv(
            &key("hidden_area"),
            format!(
                "hidden_youngs_modulus × hidden_area = {:e} N is not a usable axial rigidity (0 < EA < 1e15 N)",
                e * a
            ),
        )
    })?;
    Ok(Some(HiddenCable {
        length_m: length,
        youngs_modulus_pa: e,
        area_m2: a,
        mass_per_length_kg_m: mu,
    }))
}

#[cfg(test)]
mod tests {
    use crate::scene::{Scene, DEFAULT_SCENE_TOML};

    fn with_first_cable(extra: &str) -> String {
        let anchor = "anchor = [1.25, 1.25, 2.5]";
        DEFAULT_SCENE_TOML.replacen(anchor, &format!("{anchor}\n{extra}"), 1)
    }

    fn with_defaults(extra: &str) -> String {
        let area = "area = 50.265e-6";
        assert!(DEFAULT_SCENE_TOML.contains(area));
        DEFAULT_SCENE_TOML.replacen(area, &format!("{area}\n{extra}"), 1)
    }

    #[test]
    fn hidden_cable_parses_with_the_free_cables_material_by_default() {
        let s = Scene::from_toml_str(&with_first_cable("hidden_length = 2.5"), "t.toml").unwrap();
        let h = s.cables[0].hidden.expect("hidden");
        assert_eq!(h.length_m, 2.5);
        assert_eq!(h.ea_n(), s.cables[0].ea_n());
        assert_eq!(h.mass_per_length_kg_m, s.cables[0].mass_per_length_kg_m);
        assert!(s.cables[1].hidden.is_none());
        // A `[cable]` default applies to every cable; a cable's own value wins.
        let s = Scene::from_toml_str(
            &with_defaults("hidden_length = 2.5\nhidden_area = 2e-6"),
            "t.toml",
        )
        .unwrap();
        assert!(s.cables.iter().all(|c| c.hidden.unwrap().area_m2 == 2e-6));
        // Zero: no hidden cable (today's model).
        let s = Scene::from_toml_str(&with_first_cable("hidden_length = 0.0"), "t.toml").unwrap();
        assert!(!s.has_hidden_cable());
        assert_eq!(s, Scene::default_scene());
    }

    #[test]
    fn bad_hidden_cables_are_refused_in_one_line_naming_the_key() {
        for (extra, key) in [
            ("hidden_length = -1.0", "cables[0].hidden_length"),
            ("hidden_length = nan", "cables[0].hidden_length"),
            ("hidden_area = 1e-6", "cables[0].hidden_length"),
            (
                "hidden_length = 1.0\nhidden_youngs_modulus = 0.0",
                "cables[0].hidden_youngs_modulus",
            ),
            (
                "hidden_length = 1.0\nhidden_mass_per_length = 0.1\nhidden_weight_per_length = 1.0",
                "cables[0].hidden_weight_per_length",
            ),
            (
                "hidden_length = 1.0\nhidden_youngs_modulus = 1e30",
                "cables[0].hidden_area",
            ),
        ] {
            let e = Scene::from_toml_str(&with_first_cable(extra), "t.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains(key) && e.starts_with("t.toml"), "{extra}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let e = Scene::from_toml_str(&with_first_cable("hidden_lenght = 1.0"), "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("hidden_lenght"), "{e}");
    }

    /// Weight or mass per length, of the free cable and of its hidden part (one function,
    /// `weight_or_mass_per_length`, with the keys' prefix): the same refusals, each naming
    /// its own keys, and a weight's μ = w/|g|.
    #[test]
    fn weight_or_mass_per_length_of_free_and_hidden_cables() {
        let err = |text: &str| {
            Scene::from_toml_str(text, "t.toml")
                .unwrap_err()
                .to_string()
        };
        let zero_g = |text: String| {
            text.replacen(
                "gravity = [0.0, 0.0, -9.81]",
                "gravity = [0.0, 0.0, 0.0]",
                1,
            )
        };
        for (p, pre) in [("", ""), ("hidden_", "hidden_length = 1.0\n")] {
            let both = err(&with_first_cable(&format!(
                "{pre}{p}mass_per_length = 0.1\n{p}weight_per_length = 1.0"
            )));
            assert!(
                both.contains(&format!("cables[0].{p}weight_per_length"))
                    && both.contains(&format!(
                        "give {p}weight_per_length or {p}mass_per_length, not both"
                    )),
                "{both}"
            );
            let tiny = err(&with_first_cable(&format!(
                "{pre}{p}weight_per_length = 1e-310"
            )));
            assert!(
                tiny.contains(&format!("cables[0].{p}weight_per_length"))
                    && tiny.contains("not a usable positive number"),
                "{tiny}"
            );
            // Without gravity the free cable of a hidden one gives its mass (else its own
            // weight is refused first).
            let mass = if p.is_empty() {
                ""
            } else {
                "mass_per_length = 0.0256\n"
            };
            let no_g = err(&zero_g(with_first_cable(&format!(
                "{mass}{pre}{p}weight_per_length = 1.0"
            ))));
            assert!(
                no_g.contains(&format!(
                    "needs non-zero gravity to convert to mass; give {p}mass_per_length"
                )),
                "{no_g}"
            );
        }
        let tiny_mass = err(&with_first_cable("mass_per_length = 1e-310"));
        assert!(
            tiny_mass.contains("cables[0].mass_per_length")
                && tiny_mass.contains("not a usable positive number"),
            "{tiny_mass}"
        );
        let s = Scene::from_toml_str(
            &with_first_cable("hidden_length = 1.0\nhidden_weight_per_length = 4.905"),
            "t.toml",
        )
        .unwrap();
        assert_eq!(
            s.cables[0].hidden.unwrap().mass_per_length_kg_m,
            4.905 / 9.81
        );
    }
}
