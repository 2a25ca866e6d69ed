//! Criterion benches of the real-time cycle and its parts (release, this machine).
//! `cargo bench --bench cycle`; the per-cycle latency distribution along the trajectory is
//! measured by `cablevib bench` (percentiles, allocations, dense ratio in one run).
use cablevib::cable::{catenary_block, up_frame, ChainKind};
use cablevib::eig3::eig3;
use cablevib::estimator::{build_models, reference_analysis, Estimator, Tmin};
use cablevib::kinematics::Geometry;
use cablevib::modal::{ModalParams, ModalSolver};
use cablevib::scene::{ElementKind, Scene};
use cablevib::tension::{clarabel_reference, TensionParams, TensionSolver};
use cablevib::trajectory::circle_pose;
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use std::hint::black_box;

fn setup(n: usize, el: ElementKind) -> (Scene, Geometry, Vec<f64>) {
    let s = Scene::default_scene().with_model(el, n);
    let mut g = Geometry::new(8);
    g.update(
        s.cables.iter().map(|c| &c.anchor_m),
        &Vector3::new(0.3, 0.2, 1.0),
    )
    .unwrap();
    let t = clarabel_reference(&g, &s.wrench_n(), 60.0, 350.0).unwrap();
    (s, g, t)
}

fn parts(c: &mut Criterion) {
    let (s, g, t) = setup(40, ElementKind::Fem);
    let w = s.wrench_n();
    let mut ts = TensionSolver::new(8, TensionParams::default());
    c.bench_function("tension/active_set_warm", |b| {
        b.iter(|| black_box(ts.solve(black_box(&g), &w, 60.0, 350.0).unwrap()[0]))
    });
    c.bench_function("tension/active_set_cold", |b| {
        b.iter(|| {
            ts.reset_warm_start();
            black_box(ts.solve(black_box(&g), &w, 60.0, 350.0).unwrap()[0])
        })
    });
    c.bench_function("tension/clarabel_fresh", |b| {
        b.iter(|| black_box(clarabel_reference(black_box(&g), &w, 60.0, 350.0).unwrap()[0]))
    });
    let frame = up_frame(&s.gravity_m_s2);
    c.bench_function("cable/catenary_block", |b| {
        b.iter(|| {
            black_box(
                catenary_block(black_box(&(g.unit[0] * 0.05)), 150.0, 1.0e6, 0.251, &frame)
                    .unwrap(),
            )
        })
    });
    let models = build_models(&s, &g, &t).unwrap();
    let chain = models[4].chains[1];
    if let ChainKind::Discrete { .. } = chain.kind {
        c.bench_function("cable/chain_eval_closed_form_n40", |b| {
            b.iter(|| black_box(chain.eval(black_box(3000.0))))
        });
    }
    let mut ms = ModalSolver::new(ModalParams::default());
    ms.load(&models, s.ee_mass_kg);
    c.bench_function("modal/dynamic_stiffness_eval_8_cables", |b| {
        b.iter(|| black_box(ms.eval(black_box(3000.0)).d))
    });
    let d: nalgebra::Matrix3<f64> = ms.eval(3000.0).d.fixed_view::<3, 3>(0, 0).into_owned();
    c.bench_function("modal/eig3", |b| {
        b.iter(|| black_box(eig3(black_box(&d)).values[0]))
    });
    let r = ms.first_root(None).unwrap();
    c.bench_function("modal/first_root_warm", |b| {
        b.iter(|| black_box(ms.first_root(Some(r.lambda * (1.0 + 1e-4))).unwrap().lambda))
    });
    c.bench_function("modal/first_root_cold", |b| {
        b.iter(|| black_box(ms.first_root(None).unwrap().lambda))
    });
}

fn cycles(c: &mut Criterion) {
    for (el, n, name) in [
        (ElementKind::Fem, 40, "fem40"),
        (ElementKind::Fem, 10, "fem10"),
        (ElementKind::Continuous, 1, "continuous"),
        (ElementKind::Catenary, 40, "catenary40"),
        (ElementKind::Massless, 1, "massless"),
    ] {
        let s = Scene::default_scene().with_model(el, n);
        for ee in [true, false] {
            let p = cablevib::estimator::EstimatorParams {
                ee_mode: ee,
                ..Default::default()
            };
            let mut est = Estimator::with_params(&s, p).unwrap();
            let mut k = 0usize;
            let label = format!("cycle/{name}/{}", if ee { "f1+ee_mode" } else { "f1_only" });
            c.bench_function(&label, |b| {
                b.iter(|| {
                    k += 1;
                    black_box(
                        est.update(&circle_pose(&s, k % 4000, 4.0), Tmin::Uniform(60.0))
                            .f1_hz,
                    )
                })
            });
        }
    }
}

fn dense(c: &mut Criterion) {
    let mut group = c.benchmark_group("dense_reference");
    group.sample_size(10);
    for n in [10usize, 40] {
        let s = Scene::default_scene().with_model(ElementKind::Fem, n);
        group.bench_function(format!("spatial_fem{n}"), |b| {
            b.iter(|| {
                black_box(
                    reference_analysis(
                        &s,
                        &Vector3::new(0.3, 0.2, 1.0),
                        Tmin::Uniform(60.0),
                        false,
                    )
                    .unwrap()
                    .modes
                    .lambda[0],
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, parts, cycles, dense);
criterion_main!(benches);
