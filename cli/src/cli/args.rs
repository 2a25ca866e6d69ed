//! Options shared by the offline commands (the scene and its model overrides) and the value
//! parsers of the command line.

use super::CliError;
use crate::kinematics::unit_quaternion;
use crate::scene::{Damping, ElementKind, Scene, MAX_ELEMENTS_PER_CABLE};
use crate::study::map::Interval;
use clap::{Args, ValueEnum};
use nalgebra::Vector3;

/// Scene and model overrides shared by the offline commands.
#[derive(Debug, Args, Clone)]
pub struct SceneArgs {
    /// Scene file (TOML), or `spatial-paper` / `planar-paper` for the embedded paper robots.
    pub scene: String,
    /// End-effector position x,y,z in m (default: the scene's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub position: Option<Vector3<f64>>,
    /// End-effector orientation w,x,y,z: a unit quaternion (|norm − 1| <= 1e-3, then
    /// normalised; default: the scene's). Rigid end-effectors only: a point-mass scene
    /// refuses it, since orientation has no effect there.
    #[arg(long, value_parser = parse_quaternion, allow_hyphen_values = true, value_name = "W,X,Y,Z")]
    pub orientation: Option<[f64; 4]>,
    /// Minimum cable tension T_min in N (default: the scene's).
    #[arg(long)]
    pub t_min: Option<f64>,
    /// Elements per cable (default: the scene's).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Element model (default: the scene's).
    #[arg(long, value_enum)]
    pub element: Option<ElementArg>,
    /// The scene's effect flags.
    #[command(flatten)]
    pub effects: EffectArgs,
}

impl SceneArgs {
    /// The scene file read (a name of an embedded scene names no file).
    pub fn input_path(&self) -> std::path::PathBuf {
        std::path::PathBuf::from(&self.scene)
    }
}

/// The scene's effect flags, taken by every command that takes a scene (the offline ones
/// through [`SceneArgs`], `serve`, `demo` and `bench-ipc` directly).
#[derive(Debug, Args, Clone, Default)]
pub struct EffectArgs {
    /// Effect `sag` on or off (default: the scene's `[effects] sag`): cables on their elastic
    /// catenary (fem or continuous) or on their straight chords.
    #[arg(long, value_name = "true|false", action = clap::ArgAction::Set)]
    pub sag: Option<bool>,
}

impl EffectArgs {
    /// Whether sag is on for scene `s` with element model `element`: `--sag`, else the
    /// scene's; an error when that model cannot take it.
    fn sag_for(&self, s: &Scene, element: ElementKind) -> Result<bool, CliError> {
        let on = self.sag.unwrap_or(s.model.sag);
        if let Some(why) = crate::scene::sag_refusal(on, element) {
            let given = match self.sag {
                Some(_) => "--sag true".to_string(),
                None => format!("scene `{}` has [effects] sag = true", s.name),
            };
            return Err(CliError::Usage(format!("{given}: {why}")));
        }
        Ok(on)
    }

    /// Applies the flags to `s` (its own element model).
    pub fn apply(&self, s: &mut Scene) -> Result<(), CliError> {
        let on = self.sag_for(s, s.model.element)?;
        s.model.sag = on;
        s.model.sag_explicit |= self.sag.is_some();
        Ok(())
    }
}

/// `--element` values: the cable models of [`ElementKind`], as the command line spells them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ElementArg {
    /// Straight two-node truss elements with geometric stiffness.
    Fem,
    /// The paper's catenary element.
    Catenary,
    /// Continuous taut string / bar: the exact N → ∞ limit of fem.
    Continuous,
    /// Massless cables: springs; end-effector modes only.
    Massless,
    /// The cheapest model within the scene's f1 tolerance.
    Auto,
}

impl From<ElementArg> for ElementKind {
    fn from(e: ElementArg) -> ElementKind {
        match e {
            ElementArg::Fem => ElementKind::Fem,
            ElementArg::Catenary => ElementKind::Catenary,
            ElementArg::Continuous => ElementKind::Continuous,
            ElementArg::Massless => ElementKind::Massless,
            ElementArg::Auto => ElementKind::Auto,
        }
    }
}

/// Comma-separated finite numbers.
fn parse_numbers(s: &str) -> Result<Vec<f64>, String> {
    s.split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}")))
        .collect()
}

/// Parse `X,Y,Z` (three finite numbers).
pub fn parse_vec3(s: &str) -> Result<Vector3<f64>, String> {
    let v = parse_numbers(s)?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
        return Err(format!("expected three finite numbers X,Y,Z, got `{s}`"));
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

/// Parse `W,X,Y,Z`: a unit quaternion by [`unit_quaternion`]'s rule (normalised).
pub fn parse_quaternion(s: &str) -> Result<[f64; 4], String> {
    let v = parse_numbers(s)?;
    let q: [f64; 4] = v
        .try_into()
        .map_err(|_| format!("expected four numbers W,X,Y,Z, got `{s}`"))?;
    unit_quaternion(q).map_err(|e| e.to_string())
}

/// Parse `MIN,MAX` or a single value `V` (MIN = MAX = V).
pub fn parse_interval(s: &str) -> Result<Interval, String> {
    let v = parse_numbers(s)?;
    let (lo, hi) = match v.as_slice() {
        [a] => (*a, *a),
        [a, b] => (*a, *b),
        _ => return Err(format!("expected MIN,MAX or a single value, got `{s}`")),
    };
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Err(format!("expected finite MIN <= MAX, got `{s}`"));
    }
    Ok(Interval { lo, hi })
}

/// A list of (x, y) pairs from the command line.
#[derive(Debug, Clone, PartialEq)]
pub struct Pairs(pub Vec<(f64, f64)>);

/// Parse `A:B,C:D,...` into pairs of finite numbers.
pub fn parse_pairs(s: &str) -> Result<Pairs, String> {
    s.split(',')
        .map(|p| {
            let (a, b) = p
                .split_once(':')
                .ok_or_else(|| format!("`{p}`: expected T_MIN:HZ"))?;
            let a: f64 = a.trim().parse().map_err(|e| format!("`{a}`: {e}"))?;
            let b: f64 = b.trim().parse().map_err(|e| format!("`{b}`: {e}"))?;
            if a.is_finite() && b.is_finite() {
                Ok((a, b))
            } else {
                Err(format!("`{p}`: not finite"))
            }
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Pairs)
}

/// Apply the overrides; returns the scene with its position and T_min set.
pub fn resolve_scene(a: &SceneArgs) -> Result<Scene, CliError> {
    let mut s = Scene::load(&a.scene)?;
    if let Some(p) = a.position {
        s.ee_position_m = p;
    }
    if let Some(q) = a.orientation {
        set_orientation(&mut s, q)?;
    }
    if let Some(t) = a.t_min {
        // The one T_min rule of scene files and set-points; per-cable values are replaced.
        s.set_uniform_t_min(t)
            .map_err(|e| CliError::Usage(format!("--t-min: {e}")))?;
    }
    let element = a.element.map_or(s.model.element, ElementKind::from);
    let n = a.elements.unwrap_or(s.model.elements_per_cable);
    if n == 0 || n > MAX_ELEMENTS_PER_CABLE {
        return Err(CliError::Usage(format!(
            "--elements {n}: must be in 1..={MAX_ELEMENTS_PER_CABLE}"
        )));
    }
    let on = a.effects.sag_for(&s, element)?;
    let mut s = s.with_model(element, n);
    s.model.sag = on;
    s.model.sag_explicit |= a.effects.sag.is_some();
    Ok(s)
}

/// Set the end-effector orientation of a rigid scene; a point-mass scene refuses it.
pub fn set_orientation(s: &mut Scene, q_wxyz: [f64; 4]) -> Result<(), CliError> {
    if !s.rigid {
        return Err(CliError::Usage(format!(
            "--orientation: scene `{}` has a point-mass end-effector, where orientation has no effect (a rigid one has `effects = [\"rotation\"]`)",
            s.name
        )));
    }
    s.ee_orientation_wxyz = q_wxyz;
    Ok(())
}

/// Print the one-line warning of [`crate::estimator::sag_warning`] on stderr when `scene`
/// has sag off but its cables sag enough to change f1 at `position_m` (the scene's pose
/// elsewhere) by more than its tolerance.
pub fn warn_if_sag_matters(scene: &Scene, position_m: Option<Vector3<f64>>) {
    let pose = crate::kinematics::Pose {
        position_m: position_m.unwrap_or(scene.ee_position_m),
        orientation_wxyz: scene.ee_orientation_wxyz,
    };
    if let Some(w) = crate::estimator::sag_warning(scene, &pose) {
        // The library's line names the scene file's key; the command line adds its option.
        eprintln!("{w} or pass --sag true|false");
    }
}

/// A damping in words, SI units (`frf`'s and `simulate`'s headers, figure subtitles and
/// JSON).
pub fn damping_label(d: &Damping) -> String {
    match *d {
        Damping::None => "none".into(),
        Damping::LossFactor { eta } => format!("loss factor η = {eta}"),
        Damping::Rayleigh {
            alpha_per_s,
            beta_s,
        } => format!("Rayleigh α = {alpha_per_s} 1/s, β = {beta_s} s"),
        Damping::ModalRatio { zeta } => format!("modal ratio ζ = {zeta}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals() {
        assert_eq!(
            parse_interval("-1,1").unwrap(),
            Interval { lo: -1.0, hi: 1.0 }
        );
        assert_eq!(
            parse_interval("0.5").unwrap(),
            Interval { lo: 0.5, hi: 0.5 }
        );
        assert!(parse_interval("1,-1").is_err());
        assert!(parse_interval("a").is_err());
    }

    #[test]
    fn quaternions() {
        assert_eq!(parse_quaternion("1,0,0,0").unwrap(), [1.0, 0.0, 0.0, 0.0]);
        assert!(parse_quaternion("1,0,0")
            .unwrap_err()
            .contains("four numbers"));
        assert!(parse_quaternion("2,0,0,0").unwrap_err().contains("norm 2"));
        assert!(parse_quaternion("nan,0,0,1")
            .unwrap_err()
            .contains("finite"));
    }
}
