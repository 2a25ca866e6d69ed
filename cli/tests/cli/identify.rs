//! `cablevib identify`: a record with known modes (a closed-form 5-DOF chain, simulated
//! exactly by the testkit) written as CSV and as a ROS 2 bag in MCAP (by the pinned ROS 2
//! MCAP writer, its own CDR encoder): the modes against the known ones, the same results from
//! both files, the CSV columns `calibrate` reads, the figure, the pairing with the model, and
//! hostile records.

use cablevib_testkit::modal_record::{self, simulate, Modal, Output as Measured, Record};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

pub(super) fn run(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run cablevib")
}

pub(super) fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(ROOT).join("target/tmp/identify").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The chain of 5 masses (closed-form modes 5 … 18.7 Hz) measured at masses 1, 2, 4.
pub(super) fn chain() -> Modal {
    modal_record::chain(5.0, &[0.01, 0.005, 0.02, 0.01, 0.008])
}

/// The chain's record: 3 accelerations with 20 dB sensor noise, `duration_s` at 1 kHz.
fn chain_record(duration_s: f64, seed: u64) -> (Modal, Record) {
    let sys = chain();
    let rec = simulate(
        &sys,
        &[0, 1, 3],
        Measured::Acceleration,
        1000.0,
        duration_s,
        20.0,
        seed,
    );
    (sys, rec)
}

/// The command failed with one line on stderr containing `want`.
pub(super) fn one_line(o: &Output, want: &str) {
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    assert!(e.contains(want), "{e}");
}

/// The pinned venv with the ROS 2 MCAP writer.
pub(super) fn ros2_python() -> PathBuf {
    cablevib_testkit::pinned_venv::pinned_venv_python(
        "venv-ros2-mcap",
        &[
            ("mcap_ros2", "mcap-ros2-support", "0.5.5"),
            ("mcap", "mcap", "1.6.0"),
            ("zstandard", "zstandard", "0.23.0"),
        ],
    )
}

/// The CSV record `csv` as a ROS 2 bag `bag` (tests/py/write_ros2_bag.py), poses at `xyz`,
/// and the wrench CSV `t,fx,fy,fz` on /wrench when given.
pub(super) fn write_bag(py: &Path, csv: &Path, bag: &Path, xyz: [&str; 3], wrench: Option<&Path>) {
    let st = Command::new(py)
        .arg(PathBuf::from(ROOT).join("tests/py/write_ros2_bag.py"))
        .args([csv.to_str().unwrap(), bag.to_str().unwrap()])
        .args(xyz)
        .args(wrench.map(|w| w.to_str().unwrap()))
        .status()
        .unwrap();
    assert!(st.success());
}

/// Write `r` as CSV `t,ax,ay,az`; t is written as the MCAP reader computes it from integer
/// nanoseconds (k·10⁶ ns × 10⁻⁹), so both files hold the same doubles.
fn write_csv(r: &Record, path: &Path, edit: impl Fn(usize, &mut String)) {
    let mut s = String::from("t,ax,ay,az\n");
    for k in 0..r.t_s.len() {
        let t = (k as f64 * 1e6) * 1e-9;
        let mut line = format!("{t},{},{},{}\n", r.y[3 * k], r.y[3 * k + 1], r.y[3 * k + 2]);
        edit(k, &mut line);
        s.push_str(&line);
    }
    std::fs::write(path, s).unwrap();
}

pub(super) fn json_of(o: &Output) -> Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

pub(super) fn modes(v: &Value, w: usize) -> Vec<(f64, f64)> {
    v["windows"][w]["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["frequency_hz"].as_f64().unwrap(),
                m["damping_ratio"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// The contract's columns, in order (then one shape column per channel).
const COLUMNS: &str = "window,t_start_s,t_end_s,x_m,y_m,z_m,qw,qx,qy,qz,identified_mode,frequency_hz,frequency_std_hz,damping_ratio,damping_ratio_std,model_frequency_hz,model_mode,model_ee_participation,status";

#[test]
fn csv_and_ros2_bag_give_the_known_modes_and_identical_results() {
    let d = dir("csv_mcap");
    let (sys, rec) = chain_record(60.0, 11);
    let csv = d.join("rec.csv");
    write_csv(&rec, &csv, |_, _| {});
    // The CSV: JSON, the CSV file and the figure, the model paired at --position.
    let out = d.join("modes.csv");
    let fig = d.join("diagram.svg");
    let o = run(&[
        "identify",
        csv.to_str().unwrap(),
        "--scene",
        "spatial-paper",
        "--position",
        "0.3,0.2,1.0",
        "--json",
        "--csv",
        out.to_str().unwrap(),
        "--svg",
        fig.to_str().unwrap(),
    ]);
    let a = json_of(&o);
    let got = modes(&a, 0);
    assert_eq!(got.len(), 5, "{got:?}");
    for ((f, z), (&ft, &zt)) in got.iter().zip(sys.frequencies_hz.iter().zip(&sys.zetas)) {
        let (sf, sz) = cablevib::identify::statistical_limit(ft, zt, 60.0);
        assert!((f - ft).abs() / ft <= (3.0 * sf).max(1e-3), "{f} vs {ft}");
        assert!((z - zt).abs() / zt <= (3.0 * sz).max(0.1), "{z} vs {zt}");
    }
    // The CSV file: the agreed columns, one row per mode, the model's columns filled where paired.
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        format!("{COLUMNS},shape_ax,shape_ay,shape_az")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 5);
    for (j, r) in rows.iter().enumerate() {
        assert_eq!(r[0], "0");
        assert_eq!(r[10], (j + 1).to_string());
        // The CSV's 11 significant digits.
        assert!((r[11].parse::<f64>().unwrap() - got[j].0).abs() <= 1e-10 * got[j].0);
        assert_eq!(
            (r[3], r[4], r[5]),
            ("3.0000000000e-1", "2.0000000000e-1", "1.0000000000e0")
        );
        assert!(r[6].is_empty(), "a point mass has no orientation");
    }
    assert!(d.join("modes.csv.json").exists());
    assert!(std::fs::read_to_string(&fig).unwrap().contains("<svg"));
    // The same record as a ROS 2 bag.
    let py = ros2_python();
    let bag = d.join("rec.mcap");
    write_bag(&py, &csv, &bag, ["0.3", "0.2", "1.0"], None);
    let o = run(&[
        "identify",
        bag.to_str().unwrap(),
        "--channels",
        "linear_acceleration.x,linear_acceleration.y,linear_acceleration.z",
        "--scene",
        "spatial-paper",
        "--json",
    ]);
    let b = json_of(&o);
    for key in ["windows"] {
        let (wa, wb) = (&a[key][0], &b[key][0]);
        for k in ["t_start_s", "t_end_s", "samples", "status"] {
            assert_eq!(wa[k], wb[k], "{k}");
        }
        // The bag's poses (every 10th sample) average to the position given to the CSV run.
        let pos: Vec<f64> = wb["position_m"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for (p, q) in pos.iter().zip([0.3, 0.2, 1.0]) {
            assert!((p - q).abs() < 1e-12, "{pos:?}");
        }
        let (ma, mb) = (
            wa["modes"].as_array().unwrap(),
            wb["modes"].as_array().unwrap(),
        );
        assert_eq!(ma.len(), mb.len());
        for (x, y) in ma.iter().zip(mb) {
            for k in [
                "frequency_hz",
                "damping_ratio",
                "frequency_std_hz",
                "damping_ratio_std",
                "model",
            ] {
                assert_eq!(x[k], y[k], "{k}: CSV and MCAP differ");
            }
        }
    }
}

/// Hostile records: each a one-line error or a per-window status, nothing silently dropped.
#[test]
fn hostile_records() {
    let d = dir("hostile");
    let (_, rec) = chain_record(30.0, 3);
    // NaN and inf samples: left out, counted, the window's status says so.
    let p = d.join("nan.csv");
    write_csv(&rec, &p, |k, l| {
        if k == 5000 {
            *l = format!("{},NaN,0,0\n", (k as f64 * 1e6) * 1e-9);
        } else if k == 9000 {
            *l = format!("{},1,inf,0\n", (k as f64 * 1e6) * 1e-9);
        }
    });
    let v = json_of(&run(&["identify", p.to_str().unwrap(), "--json"]));
    assert_eq!(v["windows"][0]["status"], "gap");
    assert_eq!(v["windows"][0]["nonfinite_samples"], 2);
    // A non-finite first sample (before the first decimated one): counted in the first window.
    let p = d.join("nan_first.csv");
    write_csv(&rec, &p, |k, l| {
        if k == 0 {
            *l = "0,NaN,0,0\n".into();
        }
    });
    let v = json_of(&run(&["identify", p.to_str().unwrap(), "--json"]));
    assert_eq!(v["windows"][0]["status"], "gap");
    assert_eq!(v["windows"][0]["nonfinite_samples"], 1);
    // A gap in time: counted, status `gap`.
    let p = d.join("gap.csv");
    write_csv(&rec, &p, |k, l| {
        if (7000..7500).contains(&k) {
            l.clear();
        }
    });
    let v = json_of(&run(&["identify", p.to_str().unwrap(), "--json"]));
    assert_eq!(v["windows"][0]["status"], "gap");
    assert_eq!(v["windows"][0]["gaps"], 1);
    // Duplicated and decreasing time: one-line errors naming the sample.
    let p = d.join("dup.csv");
    write_csv(&rec, &p, |k, l| {
        if k == 3001 {
            *l = format!("{},0,0,0\n", (3000.0 * 1e6) * 1e-9);
        }
    });
    one_line(
        &run(&["identify", p.to_str().unwrap()]),
        "sample 3001: time 3 s duplicated",
    );
    let p = d.join("back.csv");
    write_csv(&rec, &p, |k, l| {
        if k == 3001 {
            *l = "1.5,0,0,0\n".into();
        }
    });
    one_line(&run(&["identify", p.to_str().unwrap()]), "goes back");
    // A sample rate too low for the band.
    let p = d.join("ok.csv");
    write_csv(&rec, &p, |_, _| {});
    one_line(
        &run(&["identify", p.to_str().unwrap(), "--to-hz", "450"]),
        "too low for the band up to 450 Hz (needs ≥ 2.5 × the band's top: lower --to-hz to ≤",
    );
    // An output over the input.
    one_line(
        &run(&[
            "identify",
            p.to_str().unwrap(),
            "--csv",
            p.to_str().unwrap(),
        ]),
        "an output is never written over an input",
    );
    // Not a number; a missing column.
    let p2 = d.join("text.csv");
    std::fs::write(&p2, "t,ax\n0,1\n0.001,abc\n").unwrap();
    one_line(
        &run(&["identify", p2.to_str().unwrap()]),
        "line 3: column ax `abc` is not a number",
    );
    one_line(
        &run(&["identify", p.to_str().unwrap(), "--channels", "gx"]),
        "--channels `gx`: no such column",
    );
    // Windows: a gap longer than a window gives that window the status no_data.
    let p = d.join("long_gap.csv");
    write_csv(&rec, &p, |k, l| {
        if (6000..14000).contains(&k) {
            l.clear();
        }
    });
    let v = json_of(&run(&[
        "identify",
        p.to_str().unwrap(),
        "--json",
        "--window",
        "6",
        "--overlap",
        "0",
    ]));
    let st: Vec<&str> = v["windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["status"].as_str().unwrap())
        .collect();
    assert!(st.contains(&"no_data"), "{st:?}");
    assert!(st.contains(&"ok"), "{st:?}");
}

/// MCAP files that are not what identify needs: a missing topic, an unknown schema, a
/// truncated bag.
#[test]
fn hostile_bags() {
    let d = dir("hostile_bags");
    let (_, rec) = chain_record(5.0, 4);
    let csv = d.join("rec.csv");
    write_csv(&rec, &csv, |_, _| {});
    let py = ros2_python();
    let bag = d.join("rec.mcap");
    write_bag(&py, &csv, &bag, ["0", "0", "1"], None);
    let b = bag.to_str().unwrap();
    one_line(&run(&["identify", b, "--topic", "/accel"]), "no message on topic /accel; topics in the file: /imu (sensor_msgs/msg/Imu), /pose (geometry_msgs/msg/PoseStamped)");
    // The pose topic as vibration: fine (its fields are channels); a field not there: refused.
    one_line(
        &run(&["identify", b, "--channels", "linear_acceleration.w"]),
        "no field `linear_acceleration.w`",
    );
    // Truncated: the file cut in the middle.
    let bytes = std::fs::read(&bag).unwrap();
    let cut = d.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    one_line(&run(&["identify", cut.to_str().unwrap()]), "cut short");
    // An unknown schema encoding on the vibration topic.
    let odd = d.join("odd.mcap");
    let script = "import sys\nfrom mcap.writer import Writer\nw = Writer(open(sys.argv[1], 'wb'))\nw.start()\ns = w.register_schema(name='my/Odd', encoding='protobuf', data=b'x')\nc = w.register_channel(topic='/imu', message_encoding='protobuf', schema_id=s)\nw.add_message(channel_id=c, log_time=1, data=b'1', publish_time=1)\nw.finish()\n";
    let st = Command::new(&py)
        .args(["-c", script, odd.to_str().unwrap()])
        .status()
        .unwrap();
    assert!(st.success());
    one_line(
        &run(&["identify", odd.to_str().unwrap(), "--topic", "/imu"]),
        "message encoding `protobuf` (schema `my/Odd`) is not decoded",
    );
}
