//! `cablevib identify RECORDING`: modal parameters from measured vibration
//! ([`crate::identify`]: SSI-cov, the stabilisation diagram, clustering, jackknife
//! uncertainty), per window, each mode beside the model's prediction at the window's pose
//! ([`crate::study::identify`]) when a scene is given; a table, CSV
//! ([`crate::report::identify`]), JSON and the stabilisation diagram.
//!
//! The recording is streamed ([`super::recording`]); the memory held is the open windows' lag
//! sums, the finished windows' results and the poses binned every [`POSE_BIN_S`] (72 bytes a
//! bin: 2.6 MB for an hour); of the finished windows only the modes are kept (and the
//! stabilisation diagram of the one drawn).

use super::args::{parse_quaternion, parse_vec3, set_orientation};
use super::figure::{self, parse_format};
use super::recording::{self, Item, Layout, ReadOptions};
use super::{json_f64, CliError};
use crate::estimator::Estimator;
use crate::identify::align::MAX_INPUT_GAP_PERIODS;
use crate::identify::{
    Aligned, Aligner, Identifier, IdentifyError, IdentifyParams, WindowResult, WindowStatus,
};
use crate::kinematics::Pose;
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::identify::{identify_csv, stabilisation_svg, Paired, WindowRows};
use crate::scene::Scene;
use crate::study::identify::{model_modes, pair, PairStatus};
use cablevib::outln;
use clap::Args;
use nalgebra::Vector3;
use serde_json::{json, Map, Value};
use std::path::PathBuf;
use std::time::Instant;

/// Poses are averaged in bins of this duration, s.
pub const POSE_BIN_S: f64 = 0.1;

/// `cablevib identify`.
#[derive(Debug, Args)]
pub struct IdentifyArgs {
    /// The recording: a CSV file (`t` in s, then channels, e.g. `ax,ay,az` in m/s²; optional
    /// pose columns `x_m,y_m,z_m[,qw,qx,qy,qz]`) or an MCAP file (a ROS 2 bag:
    /// `sensor_msgs/msg/Imu`, `geometry_msgs/msg/WrenchStamped`, poses from
    /// `geometry_msgs/msg/PoseStamped`).
    pub recording: PathBuf,
    /// Scene (TOML file, or `spatial-paper` / `planar-paper`): the model's modes at each
    /// window's pose are paired with the identified ones.
    #[arg(long)]
    pub scene: Option<String>,
    /// The end-effector's position x,y,z in m for a recording without poses (a static test).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub position: Option<Vector3<f64>>,
    /// The end-effector's orientation w,x,y,z (rigid scenes) for a recording without poses.
    #[arg(long, value_parser = parse_quaternion, allow_hyphen_values = true, value_name = "W,X,Y,Z")]
    pub orientation: Option<[f64; 4]>,
    /// Channels to identify from, comma-separated (CSV column names; MCAP field names such as
    /// `linear_acceleration.x`); default: every channel.
    #[arg(long, value_delimiter = ',')]
    pub channels: Vec<String>,
    /// Measured input channels (force or hammer, e.g. `fx` in N), comma-separated: CSV
    /// column names, or MCAP field names of the vibration topic's messages (or of
    /// --input-topic's, e.g. `wrench.force.x`). With an input
    /// the modes come from the H1 estimate of the frequency response (outputs / inputs) and
    /// a modal fit to its impulse response, instead of output-only SSI-cov.
    #[arg(long, value_delimiter = ',')]
    pub input: Vec<String>,
    /// MCAP: the topic of the vibration messages (default: the only IMU or wrench topic).
    #[arg(long)]
    pub topic: Option<String>,
    /// MCAP: the topic of the measured inputs when they are recorded on their own (e.g. a
    /// WrenchStamped topic beside the IMU's; --input names its fields). Each input is
    /// interpolated linearly at every response sample's time; a response sample outside the
    /// input's span or inside an input gap longer than 2 input periods is left out and
    /// counted in its window (`unmatched_samples`, status `gap`).
    #[arg(long)]
    pub input_topic: Option<String>,
    /// MCAP: the topic of the poses (default: the only PoseStamped topic, if any).
    #[arg(long)]
    pub pose_topic: Option<String>,
    /// Window length, s (default: the whole recording is one window).
    #[arg(long, allow_hyphen_values = true)]
    pub window: Option<f64>,
    /// Overlap of consecutive windows, a fraction in [0, 0.9].
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub overlap: f64,
    /// Lowest frequency of the band, Hz.
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub from_hz: f64,
    /// Highest frequency of the band, Hz (the sample rate must be ≥ 2.5 × this).
    #[arg(long, default_value_t = 50.0, allow_hyphen_values = true)]
    pub to_hz: f64,
    /// Highest model order of the stabilisation diagram (even, 4 ..= 200).
    #[arg(long, default_value_t = 60)]
    pub max_order: usize,
    /// Block rows of the Hankel matrix (default: max(40, max-order / channels + 2)).
    #[arg(long)]
    pub block_rows: Option<usize>,
    /// Stability: largest relative change of frequency between orders.
    #[arg(long, default_value_t = 0.01)]
    pub frequency_tol: f64,
    /// Stability: largest relative change of damping ratio between orders.
    #[arg(long, default_value_t = 0.05)]
    pub damping_tol: f64,
    /// Stability: smallest MAC between the shapes of consecutive orders.
    #[arg(long, default_value_t = 0.98)]
    pub mac_min: f64,
    /// Poles with a larger damping ratio are not modes.
    #[arg(long, default_value_t = 0.2)]
    pub max_damping: f64,
    /// Write the modes as CSV (one row per mode per window; and its .json sidecar).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the stabilisation diagram: SVG, or PNG / PDF by the extension or --format.
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png or pdf.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
    /// The window whose stabilisation diagram is drawn (from 0).
    #[arg(long, default_value_t = 0)]
    pub diagram_window: usize,
    /// One JSON object on stdout: {"windows": [{"t_start_s", "t_end_s", "status", "modes":
    /// [{"frequency_hz", "damping_ratio", "frequency_std_hz", …}]}], …}.
    #[arg(long)]
    pub json: bool,
}

/// The identification's parameters from the options.
fn params(a: &IdentifyArgs) -> IdentifyParams {
    IdentifyParams {
        from_hz: a.from_hz,
        to_hz: a.to_hz,
        max_order: a.max_order,
        block_rows: a.block_rows,
        frequency_tol: a.frequency_tol,
        damping_tol: a.damping_tol,
        mac_min: a.mac_min,
        max_damping_ratio: a.max_damping,
        window_s: a.window,
        overlap: a.overlap,
        ..IdentifyParams::default()
    }
}

/// Poses averaged in time bins (bounded memory: one bin per [`POSE_BIN_S`]).
#[derive(Debug, Default)]
struct PoseBins {
    /// (bin index, Σ position, Σ quaternion (sign-aligned), count).
    bins: Vec<(i64, [f64; 3], [f64; 4], u64)>,
    has_orientation: bool,
    nonfinite: u64,
}

impl PoseBins {
    fn add(&mut self, t: f64, p: [f64; 3], q: Option<[f64; 4]>) {
        if !(t.is_finite() && p.iter().all(|x| x.is_finite()))
            || q.is_some_and(|q| !q.iter().all(|x| x.is_finite()))
        {
            self.nonfinite += 1;
            return;
        }
        let k = (t / POSE_BIN_S).floor() as i64;
        let mut q = q.unwrap_or([1.0, 0.0, 0.0, 0.0]);
        self.has_orientation |= q != [1.0, 0.0, 0.0, 0.0];
        if let Some(first) = self.bins.first() {
            let r = first.2;
            if r[0] * q[0] + r[1] * q[1] + r[2] * q[2] + r[3] * q[3] < 0.0 {
                q = q.map(|x| -x);
            }
        }
        match self.bins.last_mut() {
            Some(b) if b.0 == k => {
                (0..3).for_each(|i| b.1[i] += p[i]);
                (0..4).for_each(|i| b.2[i] += q[i]);
                b.3 += 1;
            }
            _ => self.bins.push((k, p, q, 1)),
        }
    }

    /// The mean pose over [t0, t1).
    fn mean(&self, t0: f64, t1: f64) -> Option<([f64; 3], [f64; 4])> {
        let (mut p, mut q, mut n) = ([0.0; 3], [0.0; 4], 0u64);
        for b in &self.bins {
            let tc = (b.0 as f64 + 0.5) * POSE_BIN_S;
            if tc >= t0 && tc < t1 {
                (0..3).for_each(|i| p[i] += b.1[i]);
                (0..4).for_each(|i| q[i] += b.2[i]);
                n += b.3;
            }
        }
        if n == 0 {
            return None;
        }
        let qn = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        Some((p.map(|x| x / n as f64), q.map(|x| x / qn)))
    }
}

/// `cablevib identify`.
pub fn run(a: &IdentifyArgs) -> Result<(), CliError> {
    figure::format_needs_svg(&a.svg, a.format)?;
    let p = params(a);
    let scene = match &a.scene {
        Some(s) => {
            let mut sc = Scene::load(s)?;
            if let Some(q) = a.orientation {
                set_orientation(&mut sc, q)?;
            }
            Some(sc)
        }
        None => None,
    };
    let opts = ReadOptions {
        channels: a.channels.clone(),
        topic: a.topic.clone(),
        pose_topic: a.pose_topic.clone(),
        inputs: a.input.clone(),
        input_topic: a.input_topic.clone(),
    };
    let t0 = Instant::now();
    let mut layout: Option<Layout> = None;
    let mut id: Option<Identifier> = None;
    let mut poses = PoseBins::default();
    let mut aligner = a.input_topic.as_ref().map(|_| Aligner::new(a.input.len()));
    let shown = a.recording.display().to_string();
    let analysis =
        |e: IdentifyError| CliError::Analysis(format!("{shown}: {}", e.render("--to-hz")));
    // An aligned response sample (the inputs interpolated at its time) to the identifier.
    let feed = |id: &mut Option<Identifier>, x: Aligned<'_>| -> Result<(), IdentifyError> {
        let id = id.as_mut().expect("layout before samples");
        match x {
            Aligned::Sample { t_s, values } => id.push(t_s, values),
            Aligned::Unmatched { t_s } => id.push_unmatched(t_s),
        }
    };
    let mut sink = |item: Item<'_>| -> Result<(), CliError> {
        match item {
            Item::Layout(l) => {
                let mut i = Identifier::with_inputs(l.channels.len() - l.inputs, l.inputs, p)
                    .map_err(|e| CliError::Usage(format!("{}: {e}", a.recording.display())))?;
                // Only the drawn window's diagram is kept: memory stays bounded by the
                // windows' modes on a long record.
                i.keep_diagram_of(a.svg.as_ref().map(|_| a.diagram_window));
                id = Some(i);
                layout = Some(l.clone());
                Ok(())
            }
            Item::Sample { t_s, values } => match aligner.as_mut() {
                Some(al) => al
                    .response(t_s, values, &mut |x| feed(&mut id, x))
                    .map_err(analysis),
                None => {
                    let id = id.as_mut().expect("layout before samples");
                    id.push(t_s, values).map_err(analysis)
                }
            },
            Item::Input { t_s, values } => {
                let al = aligner.as_mut().expect("inputs on a topic of their own");
                al.input(t_s, values, &mut |x| feed(&mut id, x))
                    .map_err(analysis)
            }
            Item::Pose {
                t_s,
                position_m,
                orientation_wxyz,
            } => {
                poses.add(t_s, position_m, orientation_wxyz);
                Ok(())
            }
        }
    };
    recording::read(&a.recording, &opts, &mut sink)?;
    let alignment = match aligner {
        Some(al) => {
            let n = al.inputs();
            let dt = al.finish(&mut |x| feed(&mut id, x)).map_err(analysis)?;
            Some(Alignment {
                input_samples: n,
                input_period_s: dt,
            })
        }
        None => None,
    };
    let layout = layout.ok_or_else(|| {
        CliError::Usage(format!("{}: no vibration channel", a.recording.display()))
    })?;
    let id = id.expect("with the layout");
    let rate_hz = 1.0 / id.dt_nominal_s();
    let windows = id.finish().map_err(analysis)?;
    let identify_s = t0.elapsed().as_secs_f64();
    let rows = pair_windows(a, scene.as_ref(), &windows, &poses)?;
    let total_s = t0.elapsed().as_secs_f64();
    output(
        a,
        &layout,
        &rows,
        scene.as_ref(),
        rate_hz,
        (identify_s, total_s),
        &poses,
        alignment,
    )
}

/// Each window's pose and, with a scene, the model's modes there paired with the identified.
fn pair_windows<'a>(
    a: &IdentifyArgs,
    scene: Option<&Scene>,
    windows: &'a [WindowResult],
    poses: &PoseBins,
) -> Result<Vec<WindowRows<'a>>, CliError> {
    let mut est = match scene {
        Some(s) => Some(Estimator::new(s).map_err(|e| CliError::Analysis(e.to_string()))?),
        None => None,
    };
    let mut out = Vec::new();
    for r in windows {
        let (pos, quat) = match poses.mean(r.t_start_s, r.t_end_s) {
            Some((p, q)) => (Some(p), poses.has_orientation.then_some(q)),
            None => (a.position.map(|p| [p.x, p.y, p.z]), a.orientation.or(None)),
        };
        let base: &'static str = match r.status {
            WindowStatus::Ok => "ok",
            s => s.as_str(),
        };
        let mut paired = vec![None; r.modes.len()];
        let mut status = vec![base; r.modes.len()];
        if let (Some(s), Some(e)) = (scene, est.as_mut()) {
            if let Some(pm) = pos {
                let mut pose = Pose::in_scene(s, Vector3::new(pm[0], pm[1], pm[2]));
                if let (true, Some(q)) = (s.rigid, quat) {
                    pose.orientation_wxyz = q;
                }
                let model = model_modes(e, &pose, a.to_hz)?;
                let f: Vec<f64> = r.modes.iter().map(|m| m.frequency_hz).collect();
                for (j, (m, st)) in pair(&f, &model).into_iter().enumerate() {
                    paired[j] = m.map(|m| Paired {
                        frequency_hz: m.frequency_hz,
                        mode: m.order,
                        ee_participation: m.ee_participation,
                    });
                    if status[j] == "ok" && st != PairStatus::Ok {
                        status[j] = st.as_str();
                    }
                }
            }
        }
        out.push(WindowRows {
            result: r,
            position_m: pos,
            orientation_wxyz: quat,
            paired,
            status,
        });
    }
    Ok(out)
}

/// The measured inputs of their own topic, put on the responses' clock.
#[derive(Debug, Clone, Copy)]
struct Alignment {
    input_samples: u64,
    /// The input's nominal period, s.
    input_period_s: f64,
}

impl Alignment {
    fn json(&self, topic: &str) -> Value {
        json!({
            "topic": topic,
            "interpolation": "linear",
            "input_samples": self.input_samples,
            "input_period_s": json_f64(self.input_period_s),
            "max_gap_s": json_f64(MAX_INPUT_GAP_PERIODS * self.input_period_s),
        })
    }
}

/// The response channels (the layout's channels less the measured inputs).
fn outputs(layout: &Layout) -> &[String] {
    &layout.channels[..layout.channels.len() - layout.inputs]
}

/// The identification used: output-only SSI-cov, or H1 and its modal fit.
fn method(layout: &Layout) -> &'static str {
    if layout.inputs == 0 {
        "ssi-cov"
    } else {
        "h1-era"
    }
}

/// The JSON object of the run.
fn json_of(
    a: &IdentifyArgs,
    layout: &Layout,
    rows: &[WindowRows<'_>],
    scene: Option<&Scene>,
    rate_hz: f64,
    times: (f64, f64),
    alignment: Option<Alignment>,
) -> Value {
    let windows: Vec<Value> = rows
        .iter()
        .map(|w| {
            let r = w.result;
            let modes: Vec<Value> = r
                .modes
                .iter()
                .enumerate()
                .map(|(j, m)| {
                    let shape: Vec<Value> = outputs(layout)
                        .iter()
                        .zip(&m.shape)
                        .map(|(c, z)| json!({"channel": c, "re": json_f64(z.re), "im": json_f64(z.im)}))
                        .collect();
                    let model = w.paired[j].map_or(Value::Null, |p| {
                        json!({"frequency_hz": json_f64(p.frequency_hz), "mode": p.mode, "ee_participation": json_f64(p.ee_participation)})
                    });
                    json!({
                        "frequency_hz": json_f64(m.frequency_hz),
                        "damping_ratio": json_f64(m.damping_ratio),
                        "frequency_std_hz": json_f64(m.frequency_std_hz),
                        "damping_ratio_std": json_f64(m.damping_ratio_std),
                        "frequency_spread_hz": json_f64(m.frequency_spread_hz),
                        "stable_poles": m.stable_poles,
                        "order": m.order,
                        "jackknife_groups": m.jackknife_groups,
                        "coherence": json_f64(m.coherence),
                        "shape": shape,
                        "model": model,
                        "status": w.status[j],
                    })
                })
                .collect();
            json!({
                "index": r.index,
                "t_start_s": json_f64(r.t_start_s),
                "t_end_s": json_f64(r.t_end_s),
                "status": r.status.as_str(),
                "samples": r.samples,
                "rate_hz": json_f64(r.rate_hz),
                "gaps": r.gaps,
                "nonfinite_samples": r.nonfinite,
                "unmatched_samples": r.unmatched,
                "position_m": w.position_m.map_or(Value::Null, |p| json!(p.map(json_f64))),
                "orientation_wxyz": w.orientation_wxyz.map_or(Value::Null, |q| json!(q.map(json_f64))),
                "modes": modes,
            })
        })
        .collect();
    json!({
        "recording": a.recording.display().to_string(),
        "source": layout.source,
        "channels": outputs(layout),
        "inputs": &layout.channels[layout.channels.len() - layout.inputs..],
        "method": method(layout),
        "input_alignment": match (alignment, &a.input_topic) {
            (Some(al), Some(t)) => al.json(t),
            _ => Value::Null,
        },
        "sample_rate_hz": json_f64(rate_hz),
        "band_hz": [a.from_hz, a.to_hz],
        "scene": scene.map(|s| s.name.clone()),
        "max_order": a.max_order,
        "windows": windows,
        "identify_s": json_f64(times.0),
        "total_s": json_f64(times.1),
    })
}

#[allow(clippy::too_many_arguments)]
fn output(
    a: &IdentifyArgs,
    layout: &Layout,
    rows: &[WindowRows<'_>],
    scene: Option<&Scene>,
    rate_hz: f64,
    (identify_s, total_s): (f64, f64),
    poses: &PoseBins,
    alignment: Option<Alignment>,
) -> Result<(), CliError> {
    if a.json {
        outln!(
            "{}",
            json_of(
                a,
                layout,
                rows,
                scene,
                rate_hz,
                (identify_s, total_s),
                alignment
            )
        )?;
    } else {
        let inputs = &layout.channels[outputs(layout).len()..];
        outln!(
            "{}: {} channel(s) ({}){} at {:.4} Hz, band {} … {} Hz; {} window(s) identified in {:.3} s",
            layout.source,
            outputs(layout).len(),
            outputs(layout).join(", "),
            if inputs.is_empty() {
                String::new()
            } else {
                format!(
                    ", measured input(s) {}: H1 and its modal fit",
                    inputs.join(", ")
                )
            },
            rate_hz,
            a.from_hz,
            a.to_hz,
            rows.len(),
            identify_s
        )?;
        if let Some(al) = alignment {
            outln!(
                "{} input sample(s) every {:.6} s interpolated linearly at each response sample's time; a response sample outside their span or in a gap over {:.6} s left out (unmatched)",
                al.input_samples,
                al.input_period_s,
                MAX_INPUT_GAP_PERIODS * al.input_period_s
            )?;
        }
        if poses.nonfinite > 0 {
            outln!(
                "{} pose(s) with non-finite values left out",
                poses.nonfinite
            )?;
        }
        for w in rows {
            let r = w.result;
            let pos = w.position_m.map_or("pose unknown".to_string(), |p| {
                format!("pose ({:.4}, {:.4}, {:.4}) m", p[0], p[1], p[2])
            });
            outln!(
                "window {} [{:.3}, {:.3}] s: {}, {} mode(s), {}{}",
                r.index,
                r.t_start_s,
                r.t_end_s,
                r.status.as_str(),
                r.modes.len(),
                pos,
                if r.gaps + r.nonfinite + r.unmatched > 0 {
                    format!(
                        " ({} gap(s), {} non-finite and {} unmatched sample(s) left out)",
                        r.gaps, r.nonfinite, r.unmatched
                    )
                } else {
                    String::new()
                }
            )?;
            for (j, m) in r.modes.iter().enumerate() {
                let model = w.paired[j].map_or(String::new(), |p| {
                    format!(
                        "  model {:.4} Hz (mode {}, participation {:.2}): model − measured {:+.4} Hz",
                        p.frequency_hz,
                        p.mode,
                        p.ee_participation,
                        p.frequency_hz - m.frequency_hz
                    )
                });
                let coh = if m.coherence.is_finite() {
                    format!("  γ² {:.2}", m.coherence)
                } else {
                    String::new()
                };
                outln!(
                    "  {:>2}: {:>10.4} ± {:.4} Hz  ζ {:.4} ± {:.4}{coh}  [{}]{model}",
                    j + 1,
                    m.frequency_hz,
                    m.frequency_std_hz,
                    m.damping_ratio,
                    m.damping_ratio_std,
                    w.status[j]
                )?;
            }
        }
    }
    if let Some(path) = &a.csv {
        let mut meta = Map::new();
        meta.insert("recording".into(), json!(a.recording.display().to_string()));
        meta.insert("source".into(), json!(layout.source));
        meta.insert("channels".into(), json!(outputs(layout)));
        meta.insert(
            "inputs".into(),
            json!(&layout.channels[outputs(layout).len()..]),
        );
        meta.insert("method".into(), json!(method(layout)));
        meta.insert("band_hz".into(), json!([a.from_hz, a.to_hz]));
        meta.insert("scene".into(), json!(scene.map(|s| s.name.clone())));
        let csv = identify_csv(rows, outputs(layout), meta);
        write_csv(path, csv, &process_command_line())?;
        if !a.json {
            outln!("wrote {}", path.display())?;
        }
    }
    if let Some(path) = &a.svg {
        let (path, fmt) = figure::target(path, a.format)?;
        let w = rows.get(a.diagram_window).ok_or_else(|| {
            CliError::Usage(format!(
                "--diagram-window {}: the recording has {} window(s)",
                a.diagram_window,
                rows.len()
            ))
        })?;
        let title = format!(
            "Stabilisation diagram, window {} [{:.2}, {:.2}] s",
            w.result.index, w.result.t_start_s, w.result.t_end_s
        );
        let sub = format!(
            "{}; {} mode(s); {}, orders 2 … {}",
            layout.source,
            w.result.modes.len(),
            if layout.inputs == 0 {
                "SSI-cov"
            } else {
                "H1 and its impulse response's subspace fit (ERA)"
            },
            a.max_order
        );
        figure::write(
            &path,
            &stabilisation_svg(w, &title, &sub, (a.from_hz, a.to_hz)),
            fmt,
        )?;
        if !a.json {
            outln!("wrote {}", path.display())?;
        }
    }
    Ok(())
}
