//! The independent reference: classical RK4 on the first-order system y′ = A(s, λ) y,
//! y = (U, P), P = K U′, from U(0) = 0, P(0) = I, with K(s) built from the brief's formula
//! K = EA t tᵀ + T/(1 + T/EA)(I − t tᵀ) and the statics' own tangent and tension, inverted
//! numerically at every stage. Equal steps in s; Richardson extrapolation of n and 2n steps
//! (RK4's error is O(h⁴): (16 x₂ₙ − xₙ)/15) with |x₂ₙ − xₙ| as the error estimate. It shares
//! no code with the solver (no Magnus, no sub-segments, no Riccati).

use cablevib::elastic_catenary::Catenary;

/// U(L0) and P(L0) of the in-plane (2 × 2 each) and out-of-plane (scalar) systems.
#[derive(Clone, Copy)]
#[allow(dead_code)]
pub struct Ends {
    pub u_in: [[f64; 2]; 2],
    pub p_in: [[f64; 2]; 2],
    pub u_out: f64,
    pub p_out: f64,
}

fn compliance(cat: &Catenary, s: f64) -> ([[f64; 2]; 2], f64) {
    let t = cat.tangent_at(s);
    let tn = cat.tension_at_n(s);
    let kg = tn / (1.0 + tn / cat.ea_n);
    let mut k = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            let id = if i == j { 1.0 } else { 0.0 };
            k[i][j] = cat.ea_n * t[i] * t[j] + kg * (id - t[i] * t[j]);
        }
    }
    let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
    let c = [
        [k[1][1] / det, -k[0][1] / det],
        [-k[1][0] / det, k[0][0] / det],
    ];
    (c, 1.0 / kg)
}

/// State: in-plane U, P (columns = the two starting unit forces), out-of-plane u, p.
type State = [f64; 10];

fn deriv(cat: &Catenary, mu: f64, lambda: f64, s: f64, y: &State) -> State {
    let (c, co) = compliance(cat, s);
    let mut d = [0.0; 10];
    // y[0..4] = U row-major, y[4..8] = P row-major.
    for i in 0..2 {
        for j in 0..2 {
            d[2 * i + j] = c[i][0] * y[4 + j] + c[i][1] * y[6 + j];
            d[4 + 2 * i + j] = -lambda * mu * y[2 * i + j];
        }
    }
    d[8] = co * y[9];
    d[9] = -lambda * mu * y[8];
    d
}

/// RK4 with n equal steps.
pub fn ends(cat: &Catenary, mu: f64, lambda: f64, n: usize) -> Ends {
    let mut y: State = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0];
    let h = cat.l0_m / n as f64;
    for k in 0..n {
        let s = k as f64 * h;
        let k1 = deriv(cat, mu, lambda, s, &y);
        let y2: State = std::array::from_fn(|i| y[i] + 0.5 * h * k1[i]);
        let k2 = deriv(cat, mu, lambda, s + 0.5 * h, &y2);
        let y3: State = std::array::from_fn(|i| y[i] + 0.5 * h * k2[i]);
        let k3 = deriv(cat, mu, lambda, s + 0.5 * h, &y3);
        let y4: State = std::array::from_fn(|i| y[i] + h * k3[i]);
        let k4 = deriv(cat, mu, lambda, s + h, &y4);
        for i in 0..10 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    Ends {
        u_in: [[y[0], y[1]], [y[2], y[3]]],
        p_in: [[y[4], y[5]], [y[6], y[7]]],
        u_out: y[8],
        p_out: y[9],
    }
}

/// In-plane S = P U⁻¹ as [a, b, c] and out-of-plane s = p/u.
#[allow(dead_code)]
pub fn stiffness(e: &Ends) -> ([f64; 3], f64) {
    let u = e.u_in;
    let p = e.p_in;
    let det = u[0][0] * u[1][1] - u[0][1] * u[1][0];
    let ui = [
        [u[1][1] / det, -u[0][1] / det],
        [-u[1][0] / det, u[0][0] / det],
    ];
    let m = |i: usize, j: usize| p[i][0] * ui[0][j] + p[i][1] * ui[1][j];
    (
        [m(0, 0), 0.5 * (m(0, 1) + m(1, 0)), m(1, 1)],
        e.p_out / e.u_out,
    )
}

/// Which factor vanishes at a blocked eigenvalue.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Part {
    In,
    Out,
}

fn blocked_det(cat: &Catenary, mu: f64, lambda: f64, n: usize, part: Part) -> f64 {
    let e = ends(cat, mu, lambda, n);
    match part {
        Part::In => e.u_in[0][0] * e.u_in[1][1] - e.u_in[0][1] * e.u_in[1][0],
        Part::Out => e.u_out,
    }
}

/// The root of det U(L0; λ) of `part` in [lo, hi] (a sign change) with n steps: bisection
/// then secant to |Δλ| ≤ 1e-15 λ.
fn root(cat: &Catenary, mu: f64, lo: f64, hi: f64, n: usize, part: Part) -> f64 {
    let (mut a, mut b) = (lo, hi);
    let (mut fa, mut fb) = (
        blocked_det(cat, mu, a, n, part),
        blocked_det(cat, mu, b, n, part),
    );
    assert!(fa * fb <= 0.0, "no sign change in [{lo}, {hi}]");
    for _ in 0..200 {
        // Illinois regula falsi.
        let c = b - fb * (b - a) / (fb - fa);
        let fc = blocked_det(cat, mu, c, n, part);
        if fc * fb < 0.0 {
            a = b;
            fa = fb;
        } else {
            fa *= 0.5;
        }
        b = c;
        fb = fc;
        if (b - a).abs() <= 1e-15 * b.abs() || fc == 0.0 {
            break;
        }
    }
    b
}

/// Whether det U(L0) of `part` changes sign across [lo, hi] (with n steps).
pub fn changes(cat: &Catenary, mu: f64, lo: f64, hi: f64, n: usize, part: Part) -> bool {
    blocked_det(cat, mu, lo, n, part) * blocked_det(cat, mu, hi, n, part) <= 0.0
}

/// Which part changes sign across [lo, hi] (with n steps), if exactly one does.
pub fn part_changing(cat: &Catenary, mu: f64, lo: f64, hi: f64, n: usize) -> Option<Part> {
    let ch = |p| changes(cat, mu, lo, hi, n, p);
    match (ch(Part::In), ch(Part::Out)) {
        (true, false) => Some(Part::In),
        (false, true) => Some(Part::Out),
        _ => None,
    }
}

/// The blocked eigenvalue of `part` in [lo, hi], extrapolated from n and 2n steps, and the
/// estimate of its error.
pub fn eigenvalue(cat: &Catenary, mu: f64, lo: f64, hi: f64, n: usize, part: Part) -> (f64, f64) {
    let l1 = root(cat, mu, lo, hi, n, part);
    let l2 = root(cat, mu, lo, hi, 2 * n, part);
    ((16.0 * l2 - l1) / 15.0, (l2 - l1).abs())
}
