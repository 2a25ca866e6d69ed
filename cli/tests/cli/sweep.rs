//! The offline sweeps: every grid point is in the CSV with a status, infeasible points are
//! marked (not dropped), the SVG figures are well-formed, the FEM converges as 1/N², and
//! f1 follows a·√T_min with the coefficient of docs/model.md (section 2.2).

use cablevib::estimator::Tmin;
use cablevib::scene::{ElementKind, Scene};
use cablevib::study::accuracy::AccuracyConfig;
use cablevib::study::tmin::TminConfig;
use cablevib::study::{self, StudyError};
use cablevib::trajectory::{Circle, TrajectoryError};
use cablevib_cli::cli::{self, CliError};
use cablevib_testkit::ee_hz;
use clap::Parser;
use std::path::{Path, PathBuf};

use super::sweep_cli::{AccCli, MapCli, TminCli, TrajCli};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cablevib-sweep-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Starts with `<svg`, ends with `</svg>`, and every element is closed in order.
fn assert_well_formed_svg(path: &Path) {
    let s = std::fs::read_to_string(path).unwrap();
    assert!(
        s.starts_with("<svg"),
        "{}: does not start with <svg",
        path.display()
    );
    assert!(s.trim_end().ends_with("</svg>"), "{}", path.display());
    let mut stack: Vec<String> = Vec::new();
    let mut rest = s.as_str();
    while let Some(i) = rest.find('<') {
        let j = i + rest[i..].find('>').expect("unterminated tag");
        let tag = &rest[i + 1..j];
        assert!(!tag.contains('<'), "stray < in {tag}");
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.trim()),
                "{}",
                path.display()
            );
        } else if !tag.ends_with('/') {
            stack.push(tag.split_whitespace().next().unwrap().to_string());
        }
        rest = &rest[j + 1..];
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
    // Text outside tags must not contain a raw '&' that is not an entity.
    for (k, _) in s.match_indices('&') {
        let ent = &s[k..(k + 8).min(s.len())];
        assert!(
            ["&amp;", "&lt;", "&gt;", "&quot;", "&#39;"]
                .iter()
                .any(|e| ent.starts_with(e)),
            "raw & at {k}"
        );
    }
}

/// Header and data rows of a CSV written by the sweeps (`#` lines skipped: they write none).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect::<Vec<_>>())
        .collect();
    (header, rows)
}

const STATUSES: [&str; 6] = [
    "ok",
    "tension_infeasible",
    "outside_workspace",
    "rank_deficient",
    "not_converged",
    "invalid_input",
];

#[test]
fn map_csv_has_every_grid_point_and_marks_infeasible_ones() {
    let d = tmp("map");
    let out = d.join("m");
    // 3 x 3 x 2 grid of the spatial robot; the upper corners are tension-infeasible.
    let cli = MapCli::try_parse_from([
        "map",
        "spatial-paper",
        "--x=-1,1",
        "--y=-1,1",
        "--z=0.25,1.25",
        "--step",
        "1",
        "--threads",
        "2",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap();
    cli::map::run(&cli.a).unwrap();
    let (h, rows) = read_csv(&out.with_extension("csv"));
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (xs, ys, zs, st, f1) = (
        col("x_m"),
        col("y_m"),
        col("z_m"),
        col("status"),
        col("f1_hz"),
    );
    assert!(h.iter().any(|c| c == "tension8_n"));
    assert_eq!(rows.len(), 18, "every grid point is a row");
    for x in [-1.0, 0.0, 1.0] {
        for y in [-1.0, 0.0, 1.0] {
            for z in [0.25, 1.25] {
                let n = rows
                    .iter()
                    .filter(|r| {
                        r[xs].parse::<f64>().unwrap() == x
                            && r[ys].parse::<f64>().unwrap() == y
                            && r[zs].parse::<f64>().unwrap() == z
                    })
                    .count();
                assert_eq!(n, 1, "point ({x}, {y}, {z})");
            }
        }
    }
    let mut infeasible = 0;
    for r in &rows {
        assert!(STATUSES.contains(&r[st].as_str()), "status `{}`", r[st]);
        let f: f64 = r[f1].parse().unwrap();
        if r[st] == "ok" {
            assert!(f.is_finite() && f > 0.0);
        } else {
            assert!(f.is_nan(), "a non-ok point carries NaN, not a stale value");
            infeasible += 1;
        }
    }
    // (±1, ±1, 1.25) cannot hold T_min = 60 N within T_max = 350 N.
    assert!(infeasible >= 4, "{infeasible}");
    let upper_corner = rows
        .iter()
        .find(|r| r[xs] == "1" && r[ys] == "1" && r[zs] == "1.25")
        .unwrap();
    assert_eq!(upper_corner[st], "tension_infeasible");
    // The heat map draws those cells hatched.
    let svg = out.with_extension("svg");
    assert_well_formed_svg(&svg);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.matches("url(#hatch)").count() >= infeasible);
    // Centre of the top slice matches the single-point estimator.
    let centre = rows
        .iter()
        .find(|r| r[xs] == "0" && r[ys] == "0" && r[zs] == "1.25")
        .unwrap();
    let e = cablevib::estimator::structured_analysis(
        &Scene::default_scene(),
        &nalgebra::Vector3::new(0.0, 0.0, 1.25),
        cablevib::estimator::Tmin::Uniform(60.0),
    );
    let f: f64 = centre[f1].parse().unwrap();
    assert!((f - e.f1_hz).abs() <= 1e-7 * e.f1_hz, "{f} vs {}", e.f1_hz);
}

#[test]
fn map_result_is_independent_of_the_thread_count() {
    let args = |t: &str| {
        MapCli::try_parse_from([
            "map",
            "planar-paper",
            "--x=-1,1",
            "--y=-1,1",
            "--step",
            "0.5",
            "--threads",
            t,
            "--quiet",
        ])
        .unwrap()
        .a
    };
    let (_, one) = cli::map::compute(&args("1")).unwrap();
    let (_, three) = cli::map::compute(&args("3")).unwrap();
    assert_eq!(one.points.len(), 25);
    // Every job starts from the same cold estimator: bit for bit, whatever ran where.
    for (a, b) in one.points.iter().zip(&three.points) {
        assert_eq!(a.position_m, b.position_m);
        assert_eq!(a.estimate.status, b.estimate.status);
        assert_eq!(a.estimate.f1_hz.to_bits(), b.estimate.f1_hz.to_bits());
        assert_eq!(ee_hz(&a.estimate).to_bits(), ee_hz(&b.estimate).to_bits());
        let bits = |e: &cablevib::estimator::Estimate| {
            e.tensions().iter().map(|t| t.to_bits()).collect::<Vec<_>>()
        };
        assert_eq!(bits(&a.estimate), bits(&b.estimate));
    }
    // Planar: the minimum is at the centre (paper, conclusion 1).
    let (p, _) = one.min(study::map::MapValue::F1).unwrap();
    assert!(p.norm() < 1e-12, "{p}");
}

#[test]
fn trajectory_from_csv_and_default_circle() {
    let d = tmp("traj");
    let input = d.join("path.csv");
    std::fs::write(
        &input,
        "# test path\nt,x,y,z\n0,0,0,1.25\n0.001,0.001,0,1.25\n0.002,1.25,1.25,2.5\n",
    )
    .unwrap();
    let out = d.join("t");
    let cli = TrajCli::try_parse_from([
        "trajectory",
        "spatial-paper",
        "--csv",
        input.to_str().unwrap(),
        "--t-mins",
        "60,80",
        "--modes",
        "2",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap();
    cli::trajectory::run(&cli.a).unwrap();
    let (h, rows) = read_csv(&out.with_extension("csv"));
    let st = h.iter().position(|c| c == "status").unwrap();
    assert_eq!(rows.len(), 6, "3 poses x 2 T_min values");
    assert_eq!(rows[0][st], "ok");
    // The third pose sits on an anchor: marked, not dropped.
    assert_ne!(rows[2][st], "ok");
    assert_well_formed_svg(&out.with_extension("svg"));

    // A malformed line is reported with its line number.
    std::fs::write(&input, "0,0,0,1.25\n0.001,zero,0,1.25\n").unwrap();
    match cli::trajectory::run(&cli.a) {
        Err(CliError::Study(StudyError::Trajectory(TrajectoryError::Row { line, .. }))) => {
            assert_eq!(line, 2)
        }
        other => panic!("{other:?}"),
    }

    // Default: the paper's circle, 1 ms apart; planar f1 is higher for the higher T_min
    // at every pose (paper Fig. 8).
    let s = Scene::planar_paper();
    let tr = Circle::new(&s, 0.75, 0.2).unwrap().sampled(&s);
    assert_eq!(tr.t_s.len(), 201);
    assert!((tr.position_m[50].norm() - 0.75).abs() < 1e-12);
    let r = study::trajectory::evaluate(
        &s,
        &tr,
        &[Tmin::Uniform(20.0), Tmin::Uniform(40.0)],
        true,
        2,
        None,
    )
    .unwrap();
    let n = tr.t_s.len();
    for i in 0..n {
        let (a, b) = (&r[i].estimate, &r[n + i].estimate);
        assert!(a.is_ok() && b.is_ok());
        assert!(b.f1_hz > a.f1_hz);
    }
}

/// `study::trajectory::run` streams (chunks of `CHUNK_POSES`, bounded state) and gives what
/// the collecting evaluation gives, bit for bit, for every curve (checked against
/// `study::trajectory::evaluate`, which evaluates all poses at once into one vector): the
/// results handed to the sink, the summaries (against `TrajectoryStudy::summary` of the
/// collected points) and the CSV (row order curve-major across chunks, the later curves
/// spilled and appended). The figure keeps at most `FIGURE_MAX_POINTS` + 1 points per curve
/// (every ⌈n / cap⌉-th and the last), where before it kept every pose.
#[test]
fn trajectory_streams_in_bounded_memory_and_equals_the_collected_study() {
    use cablevib::study::trajectory::{
        run, PathSource, TrajectoryConfig, TrajectoryStudy, CHUNK_POSES, FIGURE_MAX_POINTS,
    };
    let s = Scene::planar_paper();
    let t_mins = [20.0, 40.0];
    let curves = [Tmin::Uniform(20.0), Tmin::Uniform(40.0)];
    // The circle: 12.5 s at 1 ms is 12 501 poses (> the figure cap, > 3 chunks).
    let cfg = TrajectoryConfig {
        path: PathSource::Circle {
            radius_m: 0.75,
            period_s: 12.5,
        },
        t_mins_n: t_mins.to_vec(),
        ee_mode: true,
        modes: 1,
        threads: 2,
        progress: false,
    };
    let tr = Circle::new(&s, 0.75, 12.5).unwrap().sampled(&s);
    let n = tr.t_s.len();
    assert!(n > FIGURE_MAX_POINTS, "{n}");
    assert!(n > 3 * CHUNK_POSES, "{n}");
    let all = study::trajectory::evaluate(&s, &tr, &curves, true, 2, None).unwrap();
    let mut seen = vec![Vec::new(); curves.len()];
    let mut largest_chunk = 0;
    let t = run(&s, &cfg, |c, results| {
        largest_chunk = largest_chunk.max(c.poses.len());
        for (k, r) in results.iter().enumerate() {
            seen[k].extend(r.iter().map(|p| p.estimate.f1_hz.to_bits()));
        }
        Ok::<(), StudyError>(())
    })
    .unwrap();
    assert_eq!(largest_chunk, CHUNK_POSES);
    for (k, got) in seen.iter().enumerate() {
        let want: Vec<u64> = all[k * n..(k + 1) * n]
            .iter()
            .map(|p| p.estimate.f1_hz.to_bits())
            .collect();
        assert!(got == &want, "curve {k}: streamed results differ");
    }
    let collected = TrajectoryStudy {
        samples: tr.clone(),
        poses: n,
        summaries: Vec::new(),
        t_mins_n: t_mins.to_vec(),
        points: all.clone(),
    };
    let stride = n.div_ceil(FIGURE_MAX_POINTS);
    for k in 0..curves.len() {
        assert_eq!(t.summary(k), collected.summary(k), "curve {k}");
        let fig = t.curve(k);
        assert!(fig.len() <= FIGURE_MAX_POINTS + 1, "{}", fig.len());
        assert_eq!(fig[1].position_m, tr.position_m[stride]);
        assert_eq!(fig[fig.len() - 1].position_m, tr.position_m[n - 1]);
    }
    assert_eq!((t.poses, t.samples.t_s.len()), (n, t.curve(0).len()));

    // Through the command: a CSV path of 5000 rows (CR LF ends, > one chunk), 2 curves; the
    // CSV's rows are curve-major and carry the collected results.
    let d = tmp("traj-stream");
    let input = d.join("path.csv");
    let mut text = String::from("t,x,y,z\r\n");
    for i in 0..5000 {
        let th = i as f64 * 1e-3;
        text += &format!("{th},{},{},0\r\n", 0.5 * th.cos(), 0.5 * th.sin());
    }
    std::fs::write(&input, &text).unwrap();
    let samples = cablevib::trajectory::Samples::parse_csv(&text, "x").unwrap();
    let all = study::trajectory::evaluate(&s, &samples, &curves, true, 1, None).unwrap();
    let out = d.join("t");
    let cli = TrajCli::try_parse_from([
        "trajectory",
        "planar-paper",
        "--csv",
        input.to_str().unwrap(),
        "--t-mins",
        "20,40",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap();
    cli::trajectory::run(&cli.a).unwrap();
    let (h, rows) = read_csv(&out.with_extension("csv"));
    let (ts, f1) = (
        h.iter().position(|c| c == "t_s").unwrap(),
        h.iter().position(|c| c == "f1_hz").unwrap(),
    );
    assert_eq!(rows.len(), 2 * 5000);
    for (j, row) in rows.iter().enumerate() {
        assert_eq!(row[ts], samples.t_s[j % 5000].to_string(), "row {j}");
        assert_eq!(
            row[f1],
            cablevib_cli::report::csv::num(all[j].estimate.f1_hz),
            "row {j}"
        );
    }
    // No spill file is left beside it.
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(left.len(), 4, "{left:?}");
}

#[test]
fn sweep_tmin_fits_sqrt_with_the_model_coefficient() {
    let s = Scene::planar_paper();
    let cfg = TminConfig {
        from_n: 20.0,
        to_n: 80.0,
        steps: 7,
        ee_mode: false,
        modes: 1,
    };
    let r = study::tmin::compute(&s, &cfg).unwrap();
    assert!(r.points.iter().all(|p| p.estimate.is_ok()));
    assert!((r.a - 0.10689).abs() < 1e-3 * 0.10689, "a = {}", r.a);
    assert!(r.max_rel_residual < 1e-9, "{}", r.max_rel_residual);
    assert!((study::tmin::sqrt_fit(&[4.0, 9.0], &[2.0, 3.0]) - 1.0).abs() < 1e-15);

    let d = tmp("tmin");
    let out = d.join("s");
    let cli = TminCli::try_parse_from([
        "sweep-tmin",
        "spatial-paper",
        "--from",
        "60",
        "--to",
        "120",
        "--steps",
        "4",
        "--compare",
        "60:11.245,120:15.901",
        "--modes",
        "3",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap();
    cli::sweep_tmin::run(&cli.a).unwrap();
    let (_, rows) = read_csv(&out.with_extension("csv"));
    assert_eq!(rows.len(), 4);
    assert_well_formed_svg(&out.with_extension("svg"));
    let bad = TminCli::try_parse_from(["sweep-tmin", "planar-paper", "--from", "300"]).unwrap();
    assert!(matches!(
        cli::sweep_tmin::run(&bad.a),
        Err(CliError::Study(StudyError::Param(_)))
    ));
}

#[test]
fn fem_error_falls_as_one_over_n_squared() {
    let s = Scene::default_scene();
    let cfg = AccuracyConfig {
        element_counts: vec![5, 10, 20, 40],
        cycles: 5,
        rounds: 2,
        period_s: 4.0,
    };
    let r = study::accuracy::compute(&s, &cfg).unwrap();
    let f = |n: usize| {
        r.rows
            .iter()
            .find(|x| x.element == ElementKind::Fem && x.n == Some(n))
            .unwrap()
            .f1_hz
    };
    let finf = r.f1_continuous_hz;
    assert!(finf.is_finite());
    for n in [5, 10, 20] {
        let ratio = (f(n) - finf) / (f(2 * n) - finf);
        assert!((ratio - 4.0).abs() < 0.4, "N = {n}: ratio {ratio}");
    }
    // FEM converges from above; the massless models miss the string modes entirely.
    assert!(f(40) > finf);
    let massless = r
        .rows
        .iter()
        .find(|x| x.element == ElementKind::Massless && x.geometric_stiffness)
        .unwrap();
    assert!(massless.f1_hz > 2.0 * finf);
    // Every model was timed.
    assert!(r.rows.iter().all(|x| x.f1_ns.0 > 0 && x.ee_ns.0 > 0));
    // The catenary reference is within T/(2EA)-sized terms of the continuous limit.
    assert!(((r.f1_ref_hz - finf) / finf).abs() < 1e-4);
}

#[test]
fn accuracy_command_writes_section_figures_and_data() {
    let d = tmp("acc");
    let run = |scene: &str| {
        let cli = AccCli::try_parse_from([
            "accuracy",
            scene,
            "--out-dir",
            d.to_str().unwrap(),
            "--max-elements",
            "4",
            "--cycles",
            "5",
            "--dense-max",
            "2",
            "--rounds",
            "1",
        ])
        .unwrap();
        cli::accuracy::run(&cli.a).unwrap();
    };
    run("planar-paper");
    run("spatial-paper");
    run("planar-paper"); // re-running replaces its section
    let md = std::fs::read_to_string(d.join("accuracy.md")).unwrap();
    assert_eq!(
        md.matches("<!-- accuracy:planar-paper:begin -->").count(),
        1
    );
    assert_eq!(
        md.matches("<!-- accuracy:spatial-paper:begin -->").count(),
        1
    );
    assert!(md.contains("cablevib accuracy planar-paper"));
    assert!(md.contains("| fem N=4 |"));
    // The planar robot has no out-of-plane stiffness without T/l: reported, not dropped.
    assert!(md.contains("rank_deficient"));
    for scene in ["planar-paper", "spatial-paper"] {
        for f in ["error-vs-n", "cost", "mode3"] {
            assert_well_formed_svg(&d.join("img").join(format!("accuracy-{scene}-{f}.svg")));
        }
        let (_, rows) = read_csv(&d.join("data").join(format!("accuracy-{scene}.csv")));
        assert_eq!(rows.len(), 3 + 2 * 4);
        let (_, m3) = read_csv(&d.join("data").join(format!("mode3-{scene}.csv")));
        assert_eq!(m3.len(), 4);
    }
}
