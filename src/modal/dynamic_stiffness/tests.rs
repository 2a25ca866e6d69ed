//! The loaded problem against its parts: the supported chains' pole memo and bounds.

use super::*;
use crate::cable::Segment;

/// A cable model with one supported axial chain (free segment of spring `k`).
fn supported_model(k: f64) -> CableModel {
    let chain = Chain {
        kind: ChainKind::Supported {
            free: Segment {
                k,
                m: 0.01,
                n_el: 40,
            },
            hidden: Segment {
                k: 3.0e5,
                m: 0.02,
                n_el: 25,
            },
        },
        mult: 1,
        proj: Matrix3::identity(),
    };
    CableModel {
        kc: Matrix3::zeros(),
        element_mass_kg: 0.01,
        n_el: 40,
        chains: [chain, Chain::idle(), Chain::idle()],
        n_chains: 1,
        static_stiffness: Matrix3::zeros(),
        hidden: None,
    }
}

/// The memoized poles of a supported chain are [`Chain::pole`]'s search: bit for bit
/// on the first load (the search starts in the bracket's middle), on first use and from
/// the memo, below and past the memo's size; a new load (another pose) forgets the
/// previous load's poles and starts each search from them, which finds the same root to
/// 16ε relative (the search's stopping test: its bracket 4ε wide, Newton's last step
/// 2ε). The pole intervals equal [`Chain::poles_around`] (no memo) at λ between the
/// poles and just above them, to the same 16ε.
#[test]
fn supported_pole_memo_is_the_search_per_load() {
    let mut p = LoadedChains::new();
    let close = |x: f64, y: f64| x == y || (x - y).abs() <= 16.0 * f64::EPSILON * y;
    let mut worst: f64 = 0.0;
    for (load, k) in [2.0e5, 2.01e5, 3.5e5].into_iter().enumerate() {
        let model = supported_model(k);
        p.load(&[model], 1.0, None);
        let c = model.chains[0];
        for _ in 0..2 {
            for j in 1..=SUPPORTED_POLE_MEMO + 3 {
                let (m, s) = (p.chain_pole(0, j), c.pole(j));
                if load == 0 || j > SUPPORTED_POLE_MEMO {
                    assert_eq!(m.to_bits(), s.to_bits(), "k {k} j {j}");
                }
                worst = worst.max((m - s).abs() / s / f64::EPSILON);
                assert!(close(m, s), "k {k} j {j}: {m} vs {s}");
            }
        }
        for j in 1..=SUPPORTED_POLE_MEMO + 2 {
            let pj = c.pole(j);
            for lambda in [pj * (1.0 + 1e-6), 0.5 * (pj + c.pole(j + 1))] {
                let (a, b) = p.pole_interval(lambda);
                let (a0, b0) = c.poles_around(lambda);
                assert!(close(a, a0) && close(b, b0), "k {k} λ {lambda}");
            }
        }
    }
    eprintln!("warm-started pole searches: worst difference {worst:.1} ε");
}

/// The lower bound of a supported chain's first blocked eigenvalue holds (against the
/// search, itself checked against a dense eigen-solve in `cable::supported`) over
/// stiffness and mass ratios of 1e-4 to 1e4, discrete, continuous and massless hidden
/// segments; and the pole queries that skip a chain by it answer what the full
/// computation answers, bit for bit.
#[test]
fn first_pole_lower_bound_holds_and_skipping_changes_nothing() {
    let mut rng = crate::simd::TestRng::new(0x0010_b00d);
    for trial in 0..400 {
        let n_f = [0, 1, 2, 10, 40][trial % 5];
        let n_h = if n_f == 0 { 0 } else { [1, 3, 40][trial % 3] };
        let free = Segment {
            k: rng.decades(3.0, 7.0),
            m: rng.decades(-3.0, 0.0),
            n_el: n_f,
        };
        let hidden = Segment {
            k: free.k * rng.decades(-4.0, 4.0),
            m: if trial % 7 == 0 && n_h == 1 {
                0.0
            } else {
                free.m * rng.decades(-4.0, 4.0)
            },
            n_el: n_h,
        };
        let lb = supported_pole1_lower_bound(&free, &hidden);
        let p1 = crate::cable::supported_pole(&free, &hidden, 1);
        assert!(
            lb <= p1,
            "trial {trial}: {lb} > {p1} ({free:?}, {hidden:?})"
        );
    }
    // A string-like chain (low first pole) beside a stiff supported chain.
    let mut model = supported_model(2.0e5);
    model.chains[1] = Chain {
        kind: ChainKind::Discrete {
            k: 40.0,
            m: 0.01,
            n_el: 40,
        },
        mult: 2,
        proj: Matrix3::identity(),
    };
    model.n_chains = 2;
    let mut p = LoadedChains::new();
    p.load(&[model], 1.0, None);
    let full = |lambda: f64| {
        let (mut a, mut b) = (0.0f64, f64::INFINITY);
        for i in 0..2 {
            let (lo, hi) = p.chains[i].poles_around(lambda);
            a = a.max(lo);
            b = b.min(hi);
        }
        (a, b)
    };
    assert_eq!(
        p.lowest_pole().to_bits(),
        p.chains[1].pole(1).min(p.chains[0].pole(1)).to_bits()
    );
    let top = p.chains[0].pole(3);
    for i in 0..500 {
        let lambda = top * (i as f64 / 500.0).powi(3);
        assert_eq!(p.pole_interval(lambda), full(lambda), "λ {lambda}");
        let mut s = EvalScratch::new();
        s.eval(&p, lambda);
        let (a, b) = s.last_pole_interval(&p);
        assert!(a <= lambda && lambda <= b, "λ {lambda}: ({a}, {b})");
    }
}
