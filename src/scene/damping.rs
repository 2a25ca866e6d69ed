//! `[damping]`: how the structure dissipates energy, as the scene asks for it. One kind at a
//! time; without the table there is no damping and every undamped result is unchanged.
//!
//! - `loss_factor = η` (structural, hysteretic): the stiffness becomes (1 + iη)K. A mode of
//!   natural frequency ω then has the equivalent viscous ratio ζ = η/2 at resonance.
//! - `rayleigh_alpha = α` (1/s) and/or `rayleigh_beta = β` (s): C = αM + βK, so a mode at ω
//!   has ζ(ω) = α/(2ω) + βω/2.
//! - `modal_ratio = ζ`: every mode has the viscous damping ratio ζ (no damping matrix).
//!
//! Steel wire rope dissipates mostly by friction between its wires: measured modal damping
//! ratios of ζ ≈ 0.5-2 % (η ≈ 1-4 %) are typical, higher with slack or with synthetic
//! fibre ropes. The value is the user's input: cablevib does not predict it.

/// Largest accepted loss factor η: η/2 = 1 is critical damping at resonance.
pub const MAX_LOSS_FACTOR: f64 = 2.0;
/// Largest accepted modal damping ratio ζ: ζ = 1 is critical.
pub const MAX_MODAL_RATIO: f64 = 1.0;
/// Largest accepted mass-proportional Rayleigh coefficient α, 1/s: it makes ζ ≥ 1 in every
/// mode below 0.8 kHz, far above any structure's, so only a unit slip reaches it.
pub const MAX_RAYLEIGH_ALPHA_PER_S: f64 = 1e4;
/// Largest accepted stiffness-proportional Rayleigh coefficient β, s: it makes ζ ≥ 1 in
/// every mode above 0.32 Hz, so only a unit slip reaches it.
pub const MAX_RAYLEIGH_BETA_S: f64 = 1.0;

/// The scene's damping model.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Damping {
    /// No damping (no `[damping]` table): every result is the undamped one.
    #[default]
    None,
    /// Structural damping: stiffness (1 + iη)K, η ∈ [0, [`MAX_LOSS_FACTOR`]).
    LossFactor {
        /// Loss factor η (dimensionless).
        eta: f64,
    },
    /// Rayleigh (proportional viscous) damping C = αM + βK.
    Rayleigh {
        /// Mass-proportional coefficient α, 1/s.
        alpha_per_s: f64,
        /// Stiffness-proportional coefficient β, s.
        beta_s: f64,
    },
    /// The same viscous damping ratio ζ ∈ [0, [`MAX_MODAL_RATIO`]) in every mode.
    ModalRatio {
        /// Damping ratio ζ (fraction of critical).
        zeta: f64,
    },
}

impl Damping {
    /// True when the scene has no damping.
    pub fn is_none(&self) -> bool {
        matches!(self, Damping::None)
    }

    /// The viscous damping ratio of a mode of natural circular frequency `omega_rad_s`
    /// (rad/s): 0 without damping, η/2 for a loss factor (its equivalent at resonance),
    /// α/(2ω) + βω/2 for Rayleigh damping (a rigid-body mode, ω = 0, gets ζ = 0 unless
    /// α > 0, then +∞), ζ for modal damping.
    pub fn modal_ratio(&self, omega_rad_s: f64) -> f64 {
        match *self {
            Damping::None => 0.0,
            Damping::LossFactor { eta } => 0.5 * eta,
            Damping::Rayleigh {
                alpha_per_s,
                beta_s,
            } => {
                let mass_part = if alpha_per_s == 0.0 {
                    0.0
                } else {
                    alpha_per_s / (2.0 * omega_rad_s)
                };
                mass_part + 0.5 * beta_s * omega_rad_s
            }
            Damping::ModalRatio { zeta } => zeta,
        }
    }

    /// The kind's name as in the scene file (`none`, `loss_factor`, `rayleigh`,
    /// `modal_ratio`).
    pub fn kind_str(&self) -> &'static str {
        match self {
            Damping::None => "none",
            Damping::LossFactor { .. } => "loss_factor",
            Damping::Rayleigh { .. } => "rayleigh",
            Damping::ModalRatio { .. } => "modal_ratio",
        }
    }
}
