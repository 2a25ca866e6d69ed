//! The supported chains' blocked eigenvalues of one load, memoized ([`PoleMemo`]).

use super::MAX_CHAINS;
use std::sync::atomic::{AtomicU64, Ordering};

/// A supported chain's blocked eigenvalues 1 ..= this many are memoized per load (the
/// engine asks for the lowest few, many times a cycle); higher ones are searched each time.
pub(super) const SUPPORTED_POLE_MEMO: usize = 16;

/// The loaded supported chains' blocked eigenvalues ([`Chain::pole`], a safeguarded Newton
/// search each), each computed on its first use after `load` and kept until the next:
/// f64 bits, NaN for not yet computed. Atomic (relaxed) so that the loaded problem stays
/// read-only and shareable; fixed size, no allocation. Each search starts from the value
/// the same chain's pole had at the last load where it was computed (`hint`: poses change
/// little from one cycle to the next, so Newton needs two or three steps from there); the
/// search is safeguarded by its bracket, so a stale or foreign hint only costs steps.
#[derive(Debug)]
pub(super) struct PoleMemo {
    memo: [[AtomicU64; SUPPORTED_POLE_MEMO]; MAX_CHAINS],
    hint: [[f64; SUPPORTED_POLE_MEMO]; MAX_CHAINS],
}

/// The bits of a memo entry not computed yet.
const MEMO_EMPTY: u64 = 0x7ff8_0000_0000_0000; // f64::NAN

impl PoleMemo {
    pub(super) fn new() -> PoleMemo {
        PoleMemo {
            memo: std::array::from_fn(|_| std::array::from_fn(|_| AtomicU64::new(MEMO_EMPTY))),
            hint: [[f64::NAN; SUPPORTED_POLE_MEMO]; MAX_CHAINS],
        }
    }

    /// Forget chain i's poles (each computed one kept as the next search's start).
    pub(super) fn clear(&mut self, i: usize) {
        for (e, h) in self.memo[i].iter_mut().zip(&mut self.hint[i]) {
            let bits = *e.get_mut();
            if bits != MEMO_EMPTY {
                *h = f64::from_bits(bits);
            }
            *e.get_mut() = MEMO_EMPTY;
        }
    }

    /// Pole j (1 ..= [`SUPPORTED_POLE_MEMO`]) of chain i, from `compute(hint)` on first use.
    #[inline]
    pub(super) fn get(&self, i: usize, j: usize, compute: impl FnOnce(f64) -> f64) -> f64 {
        let e = &self.memo[i][j - 1];
        let bits = e.load(Ordering::Relaxed);
        if bits != MEMO_EMPTY {
            return f64::from_bits(bits);
        }
        let v = compute(self.hint[i][j - 1]);
        e.store(v.to_bits(), Ordering::Relaxed);
        v
    }
}

impl Clone for PoleMemo {
    fn clone(&self) -> PoleMemo {
        PoleMemo {
            memo: std::array::from_fn(|i| {
                std::array::from_fn(|j| AtomicU64::new(self.memo[i][j].load(Ordering::Relaxed)))
            }),
            hint: self.hint,
        }
    }
}
