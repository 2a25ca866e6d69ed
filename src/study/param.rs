//! The studies' parameters by name, and the error that refuses one of them.
//!
//! A study refuses a configuration value with a [`ParamError`] that names the [`Param`],
//! never a command-line option: the core names a parameter as its configuration field and
//! the Python argument do (`modes`, `loss_factor`, `period_s`), and a front end renders the
//! same error with its own names ([`ParamError::render`]: the command line maps each
//! parameter to its option, `--modes`, `--loss-factor`, `--period-s`). The error is generic
//! over the set of parameters ([`ParamName`]): the service names its own the same way.

use std::fmt::Display;

/// A parameter of a study, as its configuration names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Param {
    /// Number of modes (analysis, points of a sweep, simulation).
    Modes,
    /// Solver choice of the analysis (`structured`, `dense`).
    Solver,
    /// The analysis's comparison with the dense reference.
    CompareDense,
    /// Grid step of a map, m.
    StepM,
    /// Tilt angles of a map, deg.
    TiltDeg,
    /// Tilt axis of a map.
    TiltAxis,
    /// Tilt step of a map, deg.
    TiltStepDeg,
    /// Lower tension bounds along a trajectory, N.
    TMinsN,
    /// Period of the circle, s.
    PeriodS,
    /// Radius of the circle, m.
    RadiusM,
    /// Largest element count of the accuracy study.
    MaxElements,
    /// Number of points (along a line, or frequencies of a band).
    Points,
    /// Axis of the sag comparison's line.
    Axis,
    /// Span of the sag comparison's line, m.
    SpanM,
    /// Lowest T_min of a sweep, N.
    FromN,
    /// Highest T_min of a sweep, N.
    ToN,
    /// Steps of a T_min sweep.
    Steps,
    /// Duration of a simulated path, s.
    DurationS,
    /// Sample period of a simulated path, s.
    DtS,
    /// Largest path acceleration accepted, m/s².
    MaxAccelerationMS2,
    /// Output samples between two estimator updates of a simulation.
    UpdateEvery,
    /// Time simulated after the path's end, s.
    SettleS,
    /// A simulation's accuracy target, relative to the peak deviation.
    Tolerance,
    /// Lowest frequency of a response band, Hz.
    FromHz,
    /// Highest frequency of a response band, Hz.
    ToHz,
    /// Loss factor η.
    LossFactor,
    /// Rayleigh damping (α, β).
    Rayleigh,
    /// Rayleigh damping's mass coefficient α, 1/s.
    RayleighAlpha,
    /// Rayleigh damping's stiffness coefficient β, s.
    RayleighBeta,
    /// Modal damping ratio ζ.
    ModalRatio,
    /// No damping.
    Undamped,
    /// The response checked by the dense complex LU at every frequency.
    Dense,
    /// The response checked by summation over every dense mode.
    DenseModal,
    /// Frequencies of the dense-modal check also solved by the dense LU.
    DenseLuPoints,
}

/// A set of named parameters.
pub trait ParamName: Copy + std::fmt::Debug {
    /// The parameter's name in the library (and in Python): `snake_case`, as its
    /// configuration field.
    fn name(self) -> &'static str;
}

impl ParamName for Param {
    fn name(self) -> &'static str {
        match self {
            Param::Modes => "modes",
            Param::Solver => "solver",
            Param::CompareDense => "compare_dense",
            Param::StepM => "step_m",
            Param::TiltDeg => "tilt_deg",
            Param::TiltAxis => "tilt_axis",
            Param::TiltStepDeg => "tilt_step_deg",
            Param::TMinsN => "t_mins_n",
            Param::PeriodS => "period_s",
            Param::RadiusM => "radius_m",
            Param::MaxElements => "max_elements",
            Param::Points => "points",
            Param::Axis => "axis",
            Param::SpanM => "span_m",
            Param::FromN => "from_n",
            Param::ToN => "to_n",
            Param::Steps => "steps",
            Param::DurationS => "duration_s",
            Param::DtS => "dt_s",
            Param::MaxAccelerationMS2 => "max_acceleration_m_s2",
            Param::UpdateEvery => "update_every",
            Param::SettleS => "settle_s",
            Param::Tolerance => "tolerance",
            Param::FromHz => "from_hz",
            Param::ToHz => "to_hz",
            Param::LossFactor => "loss_factor",
            Param::Rayleigh => "rayleigh",
            Param::RayleighAlpha => "rayleigh alpha",
            Param::RayleighBeta => "rayleigh beta",
            Param::ModalRatio => "modal_ratio",
            Param::Undamped => "undamped",
            Param::Dense => "dense",
            Param::DenseModal => "dense_modal",
            Param::DenseLuPoints => "dense_lu_points",
        }
    }
}

/// A parameter's value refused, with the parameter named by [`Param`] and the reason in
/// words that name no front end's option.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ParamError<P: ParamName = Param> {
    /// A value out of its range: `param value: rule`.
    Invalid {
        /// The parameter.
        param: P,
        /// The value given, as written in the message.
        value: String,
        /// The rule it breaks (`must be in 1..=256`).
        rule: String,
    },
    /// A parameter that does not apply here (to this scene, model or damping): `param:
    /// reason`, and the parameter to use instead when there is one.
    NotApplicable {
        /// The parameter.
        param: P,
        /// Why it does not apply.
        reason: String,
        /// What to use instead.
        instead: Option<P>,
    },
    /// Parameters of which at most one may be given.
    OneOf(Vec<P>),
    /// A parameter that cannot be combined with another's value.
    Conflict {
        /// The parameter.
        param: P,
        /// The other parameter.
        with: P,
        /// The other parameter's value.
        with_value: String,
        /// Why the two exclude each other.
        reason: String,
    },
}

impl<P: ParamName> ParamError<P> {
    /// `param value: rule`.
    pub fn invalid(param: P, value: impl Display, rule: impl Into<String>) -> Self {
        ParamError::Invalid {
            param,
            value: value.to_string(),
            rule: rule.into(),
        }
    }

    /// `param: reason`.
    pub fn not_applicable(param: P, reason: impl Into<String>) -> Self {
        ParamError::NotApplicable {
            param,
            reason: reason.into(),
            instead: None,
        }
    }

    /// The parameters the error names, first the refused one.
    pub fn params(&self) -> Vec<P> {
        match self {
            ParamError::Invalid { param, .. } => vec![*param],
            ParamError::NotApplicable { param, instead, .. } => {
                std::iter::once(*param).chain(*instead).collect()
            }
            ParamError::OneOf(ps) => ps.clone(),
            ParamError::Conflict { param, with, .. } => vec![*param, *with],
        }
    }

    /// The message with each parameter called `name(param)`: [`ParamName::name`] in the
    /// library and in Python, the option in the command line.
    pub fn render(&self, name: &dyn Fn(P) -> &'static str) -> String {
        match self {
            ParamError::Invalid { param, value, rule } => {
                format!("{} {value}: {rule}", name(*param))
            }
            ParamError::NotApplicable {
                param,
                reason,
                instead,
            } => match instead {
                Some(i) => format!("{}: {reason}; use {}", name(*param), name(*i)),
                None => format!("{}: {reason}", name(*param)),
            },
            ParamError::OneOf(ps) => {
                let names: Vec<&str> = ps.iter().map(|&p| name(p)).collect();
                format!("give one of {}", names.join(", "))
            }
            ParamError::Conflict {
                param,
                with,
                with_value,
                reason,
            } => format!(
                "{} with {} {with_value}: {reason}",
                name(*param),
                name(*with)
            ),
        }
    }
}

impl<P: ParamName> Display for ParamError<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.render(&P::name))
    }
}

impl<P: ParamName> std::error::Error for ParamError<P> {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_parameter_and_render_with_other_names() {
        let e: ParamError = ParamError::invalid(Param::Modes, 0, "must be in 1..=256");
        assert_eq!(e.to_string(), "modes 0: must be in 1..=256");
        assert_eq!(e.render(&|_| "--modes"), "--modes 0: must be in 1..=256");
        let e: ParamError = ParamError::OneOf(vec![Param::LossFactor, Param::ModalRatio]);
        assert_eq!(e.to_string(), "give one of loss_factor, modal_ratio");
        let e: ParamError = ParamError::NotApplicable {
            param: Param::Dense,
            reason: "no damping matrix".into(),
            instead: Some(Param::DenseModal),
        };
        assert_eq!(e.to_string(), "dense: no damping matrix; use dense_modal");
        assert_eq!(e.params(), vec![Param::Dense, Param::DenseModal]);
    }
}
