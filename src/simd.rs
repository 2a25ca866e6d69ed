//! Run-time choice of the instruction set for the vectorised kernels, written once.
//!
//! A batched kernel is one portable body (`#[inline(always)]`, plain loops over fixed-size
//! lane arrays). [`dispatch!`] wraps it in a function that, on x86-64, calls a copy of
//! the body compiled for the widest listed target feature the CPU has (AVX-512F, AVX2, …)
//! and otherwise the body itself. Every copy performs the same IEEE operations in the same
//! order (Rust never fuses or reassociates floating-point operations), so the results do
//! not depend on the CPU: the macro's second function, built for tests only, runs any one
//! tier, and each kernel's tests check that every tier the CPU has equals the portable body
//! bit for bit.

/// Defines a kernel dispatched on the CPU's target features, and a test-only function
/// that runs one chosen tier.
///
/// ```ignore
/// crate::simd::dispatch! {
///     /// Docs of the dispatched function.
///     pub fn kernel(x: &[f64], out: &mut [f64]) -> bool = kernel_body;
///     features ["avx512f", "avx2"];
///     tiers kernel_tier;
/// }
/// ```
///
/// `kernel` calls `kernel_body(x, out)` compiled for the first listed feature (widest
/// first) that `is_x86_feature_detected!` reports, else `kernel_body` as compiled for the
/// baseline target. `kernel_tier(tier, x, out)` (under `cfg(test)`) runs tier 0 (the
/// portable body), or tier i ≥ 1 (the i-th listed feature) and returns `Some` of its result,
/// or `None` when the CPU lacks that feature or there is no such tier.
macro_rules! dispatch {
    (@ret $ret:ty) => { $ret };
    (@ret) => { () };
    // One rung per feature (recursion keeps the argument list and the features apart).
    (@ladder ($($arg:ident: $ty:ty),*) ($($ret:ty)?) $body:ident;) => {};
    (@ladder ($($arg:ident: $ty:ty),*) ($($ret:ty)?) $body:ident; $feature:tt $(, $rest:tt)*) => {
        if std::arch::is_x86_feature_detected!($feature) {
            #[target_feature(enable = $feature)]
            unsafe fn tier($($arg: $ty),*) $(-> $ret)? {
                $body($($arg),*)
            }
            // SAFETY: the CPU supports the feature (checked just above).
            return unsafe { tier($($arg),*) };
        }
        $crate::simd::dispatch!(@ladder ($($arg: $ty),*) ($($ret)?) $body; $($rest),*);
    };
    (@tiers $which:ident $index:ident ($($arg:ident: $ty:ty),*) ($($ret:ty)?) $body:ident;) => {};
    (
        @tiers $which:ident $index:ident ($($arg:ident: $ty:ty),*) ($($ret:ty)?) $body:ident;
        $feature:tt $(, $rest:tt)*
    ) => {
        $index += 1;
        if $which == $index {
            if !std::arch::is_x86_feature_detected!($feature) {
                return None;
            }
            #[target_feature(enable = $feature)]
            unsafe fn tier($($arg: $ty),*) $(-> $ret)? {
                $body($($arg),*)
            }
            // SAFETY: the CPU supports the feature (checked just above).
            return Some(unsafe { tier($($arg),*) });
        }
        $crate::simd::dispatch!(
            @tiers $which $index ($($arg: $ty),*) ($($ret)?) $body; $($rest),*
        );
    };
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? = $body:ident;
        features [$($feature:tt),+ $(,)?];
        tiers $tiers:ident;
    ) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                $crate::simd::dispatch!(
                    @ladder ($($arg: $ty),*) ($($ret)?) $body; $($feature),+
                );
            }
            $body($($arg),*)
        }

        /// Runs one tier of the dispatched kernel of the same name: 0 is the portable
        /// body, i ≥ 1 the i-th listed target feature; `None` when the CPU lacks it.
        #[cfg(test)]
        #[allow(unused_assignments, unused_mut, unused_variables, clippy::unused_unit)]
        fn $tiers(
            which: usize,
            $($arg: $ty),*
        ) -> Option<$crate::simd::dispatch!(@ret $($ret)?)> {
            if which == 0 {
                return Some($body($($arg),*));
            }
            let mut index = 0usize;
            #[cfg(target_arch = "x86_64")]
            {
                $crate::simd::dispatch!(
                    @tiers which index ($($arg: $ty),*) ($($ret)?) $body; $($feature),+
                );
            }
            None
        }
    };
}
pub(crate) use dispatch;

/// Seeded pseudo-random numbers for the kernels' tier tests (SplitMix64: a fixed
/// sequence, so a failure reproduces).
#[cfg(test)]
pub(crate) struct TestRng(u64);

#[cfg(test)]
impl TestRng {
    /// The sequence of `seed`.
    pub(crate) fn new(seed: u64) -> TestRng {
        TestRng(seed)
    }

    /// The next 64 random bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// +1 or −1, evenly.
    pub(crate) fn sign(&mut self) -> f64 {
        if self.next_u64() >> 63 == 0 {
            1.0
        } else {
            -1.0
        }
    }

    /// 10^e with e uniform in [lo, hi): magnitudes spread over many decades.
    pub(crate) fn decades(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(lo + (hi - lo) * self.unit())
    }
}

#[cfg(test)]
mod tests {
    /// A kernel whose tiers are visible: the body returns its argument's sum and writes it.
    #[inline(always)]
    fn sum_body(x: &[f64], out: &mut f64) -> f64 {
        *out = x.iter().sum();
        *out
    }

    super::dispatch! {
        fn sum(x: &[f64], out: &mut f64) -> f64 = sum_body;
        features ["avx512f", "avx2"];
        tiers sum_tier;
    }

    #[test]
    fn every_tier_runs_the_body_and_no_tier_past_the_list() {
        let x = [1.0, 2.5, -0.25];
        let mut out = 0.0;
        assert_eq!(sum(&x, &mut out), 3.25);
        assert_eq!(out, 3.25);
        assert_eq!(sum_tier(0, &x, &mut out), Some(3.25));
        for which in 1..=2 {
            let r = sum_tier(which, &x, &mut out);
            assert!(r.is_none() || r == Some(3.25), "tier {which}: {r:?}");
        }
        assert_eq!(sum_tier(3, &x, &mut out), None);
    }
}
