//! Criterion benches of the sagged real-time cycle's parts next to the chord cycle's, on the
//! two sagging robots along `cablevib bench`'s circles (release, this machine).
//! `cargo bench --bench sag_parts`. Each part runs alone, pose after pose along the circle
//! (1 ms apart), so its warm starts do a real cycle's work:
//!
//! - `tension_chord`: the chord model's QP on the chords (the whole tension work of a chord
//!   cycle);
//! - `tension_sag`: the sagged tension distribution (catenaries, QP passes, Newton's step);
//! - `catenary_sweep`: one elastic catenary per cable at its final tension, warm from the
//!   last pose (a sagged tension solve needs at least two such sweeps: a step and its
//!   check);
//! - `chains_<element>`: every cable's chain set on its catenary and the pose loaded;
//! - `eval_<element>`: one evaluation of D(λ) at the pose's first root;
//! - `cycle_<chord|sag>_<element>`: the estimator's whole cycle, f1 only.
//!
//! docs/sag.md (section 3) reads them: the parts a sagged cycle cannot skip already add up
//! to more than twice the chord cycle.
use cablevib::cable::sagged::SagContinuousParams;
use cablevib::elastic_catenary::{CableChord, Catenary, SagParams, SagTrack};
use cablevib::estimator::{Estimator, EstimatorParams, Tmin};
use cablevib::kinematics::Geometry;
use cablevib::modal::sagged::{SagCableFrame, SagEndEffector};
use cablevib::modal::SagModalSolver;
use cablevib::modal::{ModalParams, CYCLE_EVALUATIONS};
use cablevib::scene::{ElementKind, Scene};
use cablevib::tension::{
    SagCable, SagTensionParams, SagTensionSolver, TensionParams, TensionSolver,
};
use cablevib::trajectory::circle_pose_with_radius;
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use std::hint::black_box;

/// Poses per revolution timed (the circle's period is longer: the parts cycle through the
/// first `POSES` ms of it).
const POSES: usize = 400;
/// FEM elements per cable (the scenes' own).
const ELEMENTS: usize = 40;

/// A scene and its bench circle: radius (m) and period (s), as docs/sag.md section 3.
struct Case {
    scene: Scene,
    radius_m: f64,
    period_s: f64,
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            scene: Scene::load("suspended-8").unwrap(),
            radius_m: 1.0,
            period_s: 4.0,
        },
        Case {
            scene: Scene::load("fast-like").unwrap(),
            radius_m: 30.0,
            period_s: 400.0,
        },
    ]
}

/// The chord geometry of every pose of the circle.
fn geometries(c: &Case) -> Vec<Geometry> {
    let s = &c.scene;
    (0..POSES)
        .map(|k| {
            let p = circle_pose_with_radius(s, k, c.period_s, c.radius_m).position_m;
            let mut g = Geometry::new(s.n_cables());
            g.update(s.cables.iter().map(|c| &c.anchor_m), &p).unwrap();
            g
        })
        .collect()
}

fn wrench6(s: &Scene) -> [f64; 6] {
    let f = s.wrench_n();
    [f.x, f.y, f.z, 0.0, 0.0, 0.0]
}

fn bounds(s: &Scene) -> (Vec<f64>, Vec<f64>) {
    let n = s.n_cables();
    (
        (0..n).map(|i| s.cable_t_min_n(i)).collect(),
        (0..n).map(|i| s.cable_t_max_n(i)).collect(),
    )
}

/// Each pose's catenaries and cable planes from the sagged tension solve.
type PoseCables = (Vec<Catenary>, Vec<SagCableFrame>, Vector3<f64>);

/// Each cable's chord in its vertical plane at pose `g`, with its material.
fn chords(s: &Scene, g: &Geometry) -> Vec<CableChord> {
    let up = -s.gravity_m_s2 / s.gravity_m_s2.norm();
    SagCable::of_scene(s)
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let l = g.unit[i] * g.length_m[i];
            let rise = l.dot(&up);
            CableChord {
                span_m: (l - up * rise).norm(),
                rise_m: rise,
                ea_n: m.ea_n,
                w_n_m: m.w_n_m,
            }
        })
        .collect()
}

fn sagged_poses(c: &Case, gs: &[Geometry]) -> Vec<PoseCables> {
    let s = &c.scene;
    let n = s.n_cables();
    let (lo, hi) = bounds(s);
    let mats = SagCable::of_scene(s);
    let mut ts = SagTensionSolver::new(n, SagTensionParams::default());
    gs.iter()
        .map(|g| {
            ts.solve(g, &mats, &s.gravity_m_s2, &wrench6(s), &lo, &hi)
                .unwrap();
            let frames = (0..n)
                .map(|i| {
                    let cat = ts.catenaries_of()[i];
                    let [h, up, _] = ts.basis(i);
                    SagCableFrame {
                        h,
                        arm_m: Vector3::zeros(),
                        end_force_n: -(h * cat.h_n + up * cat.v_end_n()),
                    }
                })
                .collect();
            (ts.catenaries_of().to_vec(), frames, ts.basis(0)[1])
        })
        .collect()
}

fn tension(c: &mut Criterion, case: &Case, gs: &[Geometry]) {
    let s = &case.scene;
    let n = s.n_cables();
    let (lo, hi) = bounds(s);
    let w = wrench6(s);
    let mats = SagCable::of_scene(s);
    let mut qp = TensionSolver::new(n, TensionParams::default());
    let mut k = 0usize;
    c.bench_function(&format!("sag_parts/{}/tension_chord", s.name), |b| {
        b.iter(|| {
            k += 1;
            black_box(qp.solve_wrench_bounds(&gs[k % POSES], &w, &lo, &hi).is_ok())
        })
    });
    let mut ts = SagTensionSolver::new(n, SagTensionParams::default());
    let mut k = 0usize;
    c.bench_function(&format!("sag_parts/{}/tension_sag", s.name), |b| {
        b.iter(|| {
            k += 1;
            let g = &gs[k % POSES];
            black_box(ts.solve(g, &mats, &s.gravity_m_s2, &w, &lo, &hi).is_ok())
        })
    });
}

fn catenaries(c: &mut Criterion, case: &Case, gs: &[Geometry], poses: &[PoseCables]) {
    let s = &case.scene;
    let chords: Vec<Vec<CableChord>> = gs.iter().map(|g| chords(s, g)).collect();
    let params = SagParams::default();
    let mut tracks: Vec<Option<SagTrack>> = vec![None; s.n_cables()];
    let mut k = 0usize;
    c.bench_function(&format!("sag_parts/{}/catenary_sweep", s.name), |b| {
        b.iter(|| {
            k += 1;
            let (cats, _, _) = &poses[k % POSES];
            for (i, chord) in chords[k % POSES].iter().enumerate() {
                let t = cats[i].tension_end_n();
                let r = chord.solve_end_tension_tracked(t, tracks[i].as_ref(), &params);
                tracks[i] = r.ok().map(|(_, _, track)| track);
            }
        })
    });
}

fn chains(c: &mut Criterion, case: &Case, poses: &[PoseCables]) {
    let s = &case.scene;
    let n = s.n_cables();
    let mu = s.cables[0].mass_per_length_kg_m;
    let ee = SagEndEffector::Point {
        mass_kg: s.ee_mass_kg,
    };
    // The real-time budget and the continuous chains' real-time mesh, as the service runs
    // them (EstimatorParams::realtime).
    let params = ModalParams {
        cycle_evaluations: CYCLE_EVALUATIONS,
        ..ModalParams::default()
    };
    for el in [ElementKind::Fem, ElementKind::Continuous] {
        let cont = el == ElementKind::Continuous;
        let mut m = if cont {
            SagModalSolver::new_continuous(params, n, SagContinuousParams::realtime())
        } else {
            SagModalSolver::new(params, n, ELEMENTS)
        };
        let set = |m: &mut SagModalSolver, (cats, frames, up): &PoseCables| {
            for (i, cat) in cats.iter().enumerate() {
                if cont {
                    m.set_continuous(i, cat, mu).unwrap();
                } else {
                    m.chain_mut(i).set_fem(cat, mu, ELEMENTS).unwrap();
                }
            }
            m.load(frames, up, &ee).unwrap();
        };
        let name = el.as_str();
        let mut k = 0usize;
        c.bench_function(&format!("sag_parts/{}/chains_{name}", s.name), |b| {
            b.iter(|| {
                k += 1;
                set(&mut m, &poses[k % POSES]);
            })
        });
        set(&mut m, &poses[0]);
        let lambda = m.first_root(None).unwrap().lambda;
        c.bench_function(&format!("sag_parts/{}/eval_{name}", s.name), |b| {
            b.iter(|| black_box(m.eval(black_box(lambda)).below))
        });
    }
}

fn cycles(c: &mut Criterion, case: &Case) {
    for el in [ElementKind::Fem, ElementKind::Continuous] {
        for sag in [false, true] {
            let mut s = case.scene.with_model(el, ELEMENTS);
            s.model.sag = sag;
            let p = EstimatorParams {
                ee_mode: false,
                ..EstimatorParams::realtime()
            };
            let mut est = Estimator::with_params(&s, p).unwrap();
            let model = if sag { "sag" } else { "chord" };
            let label = format!("sag_parts/{}/cycle_{model}_{}", s.name, el.as_str());
            let mut k = 0usize;
            c.bench_function(&label, |b| {
                b.iter(|| {
                    k += 1;
                    let pose = circle_pose_with_radius(&s, k % POSES, case.period_s, case.radius_m);
                    black_box(est.update(&pose, Tmin::Scene).f1_hz)
                })
            });
        }
    }
}

fn parts(c: &mut Criterion) {
    for case in cases() {
        let gs = geometries(&case);
        let poses = sagged_poses(&case, &gs);
        tension(c, &case, &gs);
        catenaries(c, &case, &gs, &poses);
        chains(c, &case, &poses);
        cycles(c, &case);
    }
}

criterion_group!(benches, parts);
criterion_main!(benches);
