//! Multi-DOF systems with closed-form modes, 60 s at 1 kHz, 3 channels, sensor noise at
//! 20 dB SNR: the identified frequencies and damping ratios against the known ones.

use cablevib::identify::ssi::mac;
use cablevib::identify::{identify, IdentifyParams, WindowStatus};
use cablevib_testkit::modal_record::{chain, check_modes, close_pair, simulate, Output};

/// The chain measured at masses 1, 2 and 4 (accelerations): five modes 5 … 18.7 Hz, damping
/// ratios 0.5 … 2 %.
#[test]
fn chain_five_modes_three_accelerometers() {
    let zetas = [0.01, 0.005, 0.02, 0.01, 0.008];
    let sys = chain(5.0, &zetas);
    let rec = simulate(
        &sys,
        &[0, 1, 3],
        Output::Acceleration,
        1000.0,
        60.0,
        20.0,
        11,
    );
    let p = IdentifyParams::default();
    let t0 = std::time::Instant::now();
    let w = identify(&rec.t_s, &rec.y, rec.channels, &p).unwrap();
    println!("identified in {:.3} s", t0.elapsed().as_secs_f64());
    assert_eq!(w.len(), 1);
    assert_eq!(w[0].status, WindowStatus::Ok);
    let worst = check_modes(&w[0].modes, &sys.frequencies_hz, &zetas, 60.0);
    println!(
        "worst error / tolerance: frequency {:.2}, damping {:.2}",
        worst.0, worst.1
    );
}

/// Two identical oscillators (m, k) coupled by k_c, ω₁² = k/m, ω₂² = (k + 2k_c)/m with
/// shapes (1, 1)/√(2m) and (1, −1)/√(2m), 1 % apart; a third oscillator at 6 Hz on its own.
/// The pair must come out as two modes, each within its tolerance.
#[test]
fn modes_one_percent_apart_are_separated() {
    let sys = close_pair();
    let rec = simulate(
        &sys,
        &[0, 1, 2],
        Output::Acceleration,
        1000.0,
        60.0,
        20.0,
        23,
    );
    let w = identify(&rec.t_s, &rec.y, rec.channels, &IdentifyParams::default()).unwrap();
    assert_eq!(w[0].status, WindowStatus::Ok);
    check_modes(&w[0].modes, &sys.frequencies_hz, &sys.zetas, 60.0);
    // The pair's shapes: the in-phase and the anti-phase motion of the two masses.
    // The MAC against the closed-form shapes at the three sensors. Two modes 1 % apart mix
    // by an angle of about σ_f / Δf ≈ 0.3 … 0.4 rad here (σ_f ≈ 0.3 … 0.4 % of f, the
    // record's limit), so MAC ≥ cos²(0.45) ≈ 0.8 is what the record allows; each shape must
    // also be far from the other mode's (MAC < 0.2).
    let c = |x: f64| num_complex::Complex64::new(x, 0.0);
    let (s1, s2) = (&w[0].modes[1].shape, &w[0].modes[2].shape);
    let (m1, m2) = (
        mac(s1, &[c(1.0), c(1.0), c(0.0)]),
        mac(s2, &[c(1.0), c(-1.0), c(0.0)]),
    );
    println!("MAC in-phase {m1:.4}, anti-phase {m2:.4}");
    assert!(m1 > 0.8 && m2 > 0.8, "shapes {s1:?} {s2:?}");
    let cross = mac(s1, &[c(1.0), c(-1.0), c(0.0)]).max(mac(s2, &[c(1.0), c(1.0), c(0.0)]));
    assert!(
        cross < 0.2,
        "the pair's shapes are not told apart: cross MAC {cross}"
    );
}
