//! The stabilisation diagram and the clustering of its stable poles into modes.
//!
//! A pole of order n is compared with the poles of the order below (n − 2): the one
//! nearest in |Δf|/f + (1 − MAC) is its neighbour. It is *stable* when, against that
//! neighbour, the frequency moved by at most `frequency_tol` (relative), the damping ratio by
//! at most `damping_tol` (relative) and the MAC is at least `mac_min`; the diagram also marks
//! the poles stable in frequency only, or in frequency and damping, or in frequency and shape.
//!
//! Stable poles are clustered from the highest order down: at each order the poles are
//! matched one to one to the clusters (a cluster takes at most one pole per order, so two
//! modes close in frequency stay apart however close), greedily by the distance
//! |Δf|/f + (1 − MAC) to the cluster's first pole, admitting a match within `frequency_tol`
//! and `mac_min`; an unmatched pole opens a new cluster. A cluster with poles of at least
//! `min_stable_fraction` of the orders (and at least 3) is a mode: its frequency and
//! damping ratio are the medians of its poles, its shape that of the pole whose frequency is
//! the median.

use super::ssi::{mac, Pole};
use super::IdentifyParams;

/// How a pole compares with the order below.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stability {
    /// No neighbour within the frequency tolerance (or the lowest order).
    New,
    /// Frequency stable only.
    Frequency,
    /// Frequency and damping stable.
    FrequencyDamping,
    /// Frequency and shape stable.
    FrequencyShape,
    /// Frequency, damping and shape stable.
    Stable,
}

impl Stability {
    /// Short name (figure legend, JSON).
    pub fn as_str(self) -> &'static str {
        match self {
            Stability::New => "new",
            Stability::Frequency => "f",
            Stability::FrequencyDamping => "f_damping",
            Stability::FrequencyShape => "f_shape",
            Stability::Stable => "stable",
        }
    }
}

/// One pole of the diagram with its stability.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagramPole {
    /// The pole.
    pub pole: Pole,
    /// Its stability against the order below.
    pub stability: Stability,
}

/// A cluster: indices into the diagram's poles.
#[derive(Debug, Clone)]
pub struct Cluster {
    /// The poles, highest order first.
    pub members: Vec<usize>,
}

/// Distance |Δf|/f + (1 − MAC) of two poles.
pub fn distance(a: &Pole, b: &Pole) -> f64 {
    (a.frequency_hz - b.frequency_hz).abs() / b.frequency_hz + (1.0 - mac(&a.shape, &b.shape))
}

/// The stability of every pole (`by_order[k]` the poles of the k-th order, ascending).
pub fn classify(by_order: Vec<Vec<Pole>>, p: &IdentifyParams) -> Vec<DiagramPole> {
    let mut out = Vec::new();
    let mut below: Vec<Pole> = Vec::new();
    for poles in by_order {
        for pole in &poles {
            let near = below
                .iter()
                .min_by(|a, b| distance(pole, a).total_cmp(&distance(pole, b)));
            let stability = match near {
                None => Stability::New,
                Some(q) => {
                    let df = (pole.frequency_hz - q.frequency_hz).abs() / q.frequency_hz;
                    let dz = (pole.damping_ratio - q.damping_ratio).abs() / q.damping_ratio;
                    let shape = mac(&pole.shape, &q.shape) >= p.mac_min;
                    match (df <= p.frequency_tol, dz <= p.damping_tol, shape) {
                        (false, _, _) => Stability::New,
                        (true, true, true) => Stability::Stable,
                        (true, true, false) => Stability::FrequencyDamping,
                        (true, false, true) => Stability::FrequencyShape,
                        (true, false, false) => Stability::Frequency,
                    }
                }
            };
            out.push(DiagramPole {
                pole: pole.clone(),
                stability,
            });
        }
        below = poles;
    }
    out
}

/// The clusters of the stable poles that are modes, ascending in frequency.
pub fn cluster(diagram: &[DiagramPole], p: &IdentifyParams, orders: usize) -> Vec<Cluster> {
    let mut stable: Vec<usize> = (0..diagram.len())
        .filter(|&i| diagram[i].stability == Stability::Stable)
        .collect();
    stable.sort_by(|&a, &b| diagram[b].pole.order.cmp(&diagram[a].pole.order));
    let mut clusters: Vec<Cluster> = Vec::new();
    let mut k = 0;
    while k < stable.len() {
        let order = diagram[stable[k]].pole.order;
        let end = k + stable[k..]
            .iter()
            .take_while(|&&i| diagram[i].pole.order == order)
            .count();
        // Candidate (distance, pole, cluster) pairs within the tolerances, nearest first.
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for &i in &stable[k..end] {
            let pi = &diagram[i].pole;
            for (c, cl) in clusters.iter().enumerate() {
                let head = &diagram[cl.members[0]].pole;
                let df = (pi.frequency_hz - head.frequency_hz).abs() / head.frequency_hz;
                if df <= p.frequency_tol && mac(&pi.shape, &head.shape) >= p.mac_min {
                    pairs.push((distance(pi, head), i, c));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut pole_used = vec![false; diagram.len()];
        let mut cluster_used = vec![false; clusters.len()];
        for (_, i, c) in pairs {
            if !pole_used[i] && !cluster_used[c] {
                pole_used[i] = true;
                cluster_used[c] = true;
                clusters[c].members.push(i);
            }
        }
        for &i in &stable[k..end] {
            if !pole_used[i] {
                clusters.push(Cluster { members: vec![i] });
            }
        }
        k = end;
    }
    let need = ((p.min_stable_fraction * orders as f64).ceil() as usize).max(3);
    clusters.retain(|c| c.members.len() >= need);
    let median_f = |c: &Cluster| median(c.members.iter().map(|&i| diagram[i].pole.frequency_hz));
    clusters.sort_by(|a, b| median_f(a).total_cmp(&median_f(b)));
    clusters
}

/// The median of `xs` (NaN for none).
pub fn median(xs: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = xs.collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}
