//! The scalar a chain is evaluated in: f64 (λ = ω², the undamped problem) or
//! [`Complex64`] (a complex λ: the damped frequency response, where the loss-factor and
//! Rayleigh forms (1 + iη)K − ω²M and (1 + iωβ)K − (ω² − iωα)M are a complex multiple of
//! K − λM, see `modal::frf`).
//!
//! Why a trait: the chain recurrences (uniform, continuous, sagged) are written once over
//! it and instantiated for both; the f64 instance performs the same operations in the same
//! order as before, so the undamped results are unchanged bit for bit. The blocked count
//! only has a meaning on the real axis: a complex pivot is never counted as negative.

use num_complex::Complex64;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// f64 or [`Complex64`]: what a chain recurrence needs of its scalar.
pub trait ChainScalar:
    Copy
    + std::fmt::Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// True for f64.
    const REAL: bool;
    /// The real number `x` as this scalar.
    fn re(x: f64) -> Self;
    /// Exactly zero.
    fn is_zero(self) -> bool;
    /// Strictly negative real (never true for a complex scalar): the pivot count.
    fn is_negative(self) -> bool;
    /// ≤ 0 on the real axis (never true for a complex scalar): where a real evaluation
    /// takes its static branch.
    fn is_nonpositive(self) -> bool;
    /// Modulus.
    fn modulus(self) -> f64;
    /// 1/x.
    fn recip(self) -> Self;
    /// Principal square root.
    fn sqrt(self) -> Self;
    /// (sin x, cos x).
    fn sin_cos(self) -> (Self, Self);
    /// All parts finite.
    fn finite(self) -> bool;
}

impl ChainScalar for f64 {
    const REAL: bool = true;
    #[inline(always)]
    fn re(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn is_zero(self) -> bool {
        self == 0.0
    }
    #[inline(always)]
    fn is_negative(self) -> bool {
        self < 0.0
    }
    #[inline(always)]
    fn is_nonpositive(self) -> bool {
        self <= 0.0
    }
    #[inline(always)]
    fn modulus(self) -> f64 {
        self.abs()
    }
    #[inline(always)]
    fn recip(self) -> f64 {
        1.0 / self
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (f64, f64) {
        f64::sin_cos(self)
    }
    #[inline(always)]
    fn finite(self) -> bool {
        self.is_finite()
    }
}

impl ChainScalar for Complex64 {
    const REAL: bool = false;
    #[inline(always)]
    fn re(x: f64) -> Complex64 {
        Complex64::new(x, 0.0)
    }
    #[inline(always)]
    fn is_zero(self) -> bool {
        self.re == 0.0 && self.im == 0.0
    }
    #[inline(always)]
    fn is_negative(self) -> bool {
        false
    }
    #[inline(always)]
    fn is_nonpositive(self) -> bool {
        false
    }
    #[inline(always)]
    fn modulus(self) -> f64 {
        self.norm()
    }
    #[inline(always)]
    fn recip(self) -> Complex64 {
        self.inv()
    }
    #[inline(always)]
    fn sqrt(self) -> Complex64 {
        Complex64::sqrt(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Complex64, Complex64) {
        (self.sin(), self.cos())
    }
    #[inline(always)]
    fn finite(self) -> bool {
        self.is_finite()
    }
}
