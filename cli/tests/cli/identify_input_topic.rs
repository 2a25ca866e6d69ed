//! `cablevib identify BAG --input-topic /wrench --input wrench.force.x`: the measured force
//! recorded as `geometry_msgs/msg/WrenchStamped` on a topic of its own beside the
//! `sensor_msgs/msg/Imu` responses, on its own clock (1 kHz, half a period after the IMU's
//! samples: linear interpolation's worst phase), written by the pinned ROS 2 MCAP writer in log-time order as `ros2 bag record`
//! writes it. The reference: the chain's closed-form modes (testkit), with the tolerances of
//! the CSV `--input` test; the same signals as one CSV on one clock; and, independently of the
//! aligner's code, the one-clock CSV whose force column is the interpolation in closed form.

use super::identify::{dir, json_of, modes, one_line, ros2_python, run, write_bag};
use super::identify_input::{assert_known, forced_chain, write};
use cablevib_testkit::modal_record::Record;
use std::path::Path;

/// The IMU's accelerations as responses, the wrench topic's force x as the input.
const WRENCH_TOPIC: [&str; 6] = [
    "--channels",
    "linear_acceleration.x,linear_acceleration.y,linear_acceleration.z",
    "--input-topic",
    "/wrench",
    "--input",
    "wrench.force.x",
];

/// The force on the chain is held over each 1 ms step (testkit), so a sensor sampling it
/// `phase_s` after the IMU's sample k reads sample k's force exactly: the wrench stream is
/// what a force sensor on its own clock records. `keep(k)`: which wrench samples are written.
fn write_wrench(path: &Path, rec: &Record, phase_s: f64, keep: impl Fn(usize) -> bool) {
    write(path, rec.t_s.len(), "fx,fy,fz", |k| {
        if keep(k) {
            vec![rec.u[k], 0.0, 0.0]
        } else {
            Vec::new()
        }
    });
    // `write` puts t = k ms; shift to the sensor's phase and drop the rows not kept.
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = String::from("t,fx,fy,fz\n");
    for line in text.lines().skip(1) {
        let mut it = line.splitn(2, ',');
        let t: f64 = it.next().unwrap().parse().unwrap();
        if let Some(rest) = it.next().filter(|r| !r.is_empty()) {
            out.push_str(&format!("{},{rest}\n", t + phase_s));
        }
    }
    std::fs::write(path, out).unwrap();
}

/// The IMU's accelerations from sample `from` on, as the CSV `t,ax,ay,az` the bag writer
/// reads.
fn write_imu(path: &Path, rec: &Record, from: usize) {
    let text = {
        let mut s = String::from("t,ax,ay,az\n");
        for k in from..rec.t_s.len() {
            let y = &rec.y[3 * k..3 * k + 3];
            s.push_str(&format!(
                "{},{},{},{}\n",
                (k as f64 * 1e6) * 1e-9,
                y[0],
                y[1],
                y[2]
            ));
        }
        s
    };
    std::fs::write(path, text).unwrap();
}

#[test]
fn wrench_topic_beside_imu_gives_the_known_modes() {
    let d = dir("input_topic");
    let sys = super::identify::chain();
    // The record of the CSV --input test (same system, sensors, seed).
    let rec = forced_chain(60.0, 5);
    // One clock: the CSV with the force column.
    let csv = d.join("forced.csv");
    write(&csv, rec.t_s.len(), "ax,ay,az,fx", |k| rec.sample(k));
    let a = json_of(&run(&[
        "identify",
        csv.to_str().unwrap(),
        "--input",
        "fx",
        "--json",
    ]));
    // Two clocks: the IMU from sample 1 on (so the wrench, from 0.5 ms, spans every IMU
    // sample), the wrench 0.5 ms after each IMU sample.
    let (imu, wrench, bag) = (d.join("imu.csv"), d.join("wrench.csv"), d.join("rec.mcap"));
    write_imu(&imu, &rec, 1);
    write_wrench(&wrench, &rec, 0.5e-3, |_| true);
    // The interpolation in closed form: at IMU sample k ≥ 1 the wrench samples around it
    // read f(k−1) and f(k), halfway: u = (f(k−1) + f(k)) / 2.
    let closed = d.join("interpolated.csv");
    write(&closed, rec.t_s.len() - 1, "ax,ay,az,fx", |j| {
        let k = j + 1;
        let mut v = rec.y[3 * k..3 * k + 3].to_vec();
        v.push(0.5 * (rec.u[k - 1] + rec.u[k]));
        v
    });
    let c = json_of(&run(&[
        "identify",
        closed.to_str().unwrap(),
        "--input",
        "fx",
        "--json",
    ]));
    let py = ros2_python();
    write_bag(&py, &imu, &bag, ["0", "0", "1"], Some(&wrench));
    let b = bag.to_str().unwrap();
    let o = run(&[&["identify", b][..], &WRENCH_TOPIC, &["--json"]].concat());
    let v = json_of(&o);
    assert_eq!(v["method"], "h1-era");
    assert_eq!(v["inputs"], serde_json::json!(["wrench.force.x"]));
    let al = &v["input_alignment"];
    assert_eq!(al["topic"], "/wrench");
    assert_eq!(al["input_samples"], rec.t_s.len());
    assert!(
        (al["input_period_s"].as_f64().unwrap() - 1e-3).abs() < 1e-9,
        "{al}"
    );
    let w = &v["windows"][0];
    assert_eq!(w["status"], "ok", "{w}");
    assert_eq!(w["unmatched_samples"], 0);
    let got = modes(&v, 0);
    let csv_modes = modes(&a, 0);
    for ((f, z), (fc, zc)) in got.iter().zip(&csv_modes) {
        println!(
            "wrench topic: {f:.5} Hz ζ {z:.5}; one-clock CSV {fc:.5} Hz ζ {zc:.5}: Δf {:.2e}, Δζ/ζ {:.2e}",
            (f - fc).abs() / fc,
            (z - zc).abs() / zc
        );
    }
    assert_known(&got, &sys, "wrench topic");
    // The closed-form interpolation gives the same modes (the same numbers but for the
    // rounding of the interpolation weight from nanosecond stamps, and the time origin).
    let closed_modes = modes(&c, 0);
    assert_eq!(got.len(), closed_modes.len());
    for ((f, z), (fc, zc)) in got.iter().zip(&closed_modes) {
        assert!((f - fc).abs() / fc <= 1e-6, "{f} vs closed form {fc}");
        assert!((z - zc).abs() / zc <= 1e-6, "ζ {z} vs closed form {zc}");
    }
    // Against the one-clock CSV: the interpolated force is the true force through the
    // two-tap filter (f(k−1) + f(k))/2 (gain within 0.4 % of 1 below 20 Hz, a delay of half
    // a period: poles unchanged), and the record lacks one sample: the estimates of the same
    // noise agree far inside the statistical tolerances (0.1 % frequency, 10 % damping).
    assert_eq!(got.len(), csv_modes.len());
    for ((f, z), (fc, zc)) in got.iter().zip(&csv_modes) {
        assert!((f - fc).abs() / fc <= FREQ_VS_CSV, "{f} vs {fc}");
        assert!((z - zc).abs() / zc <= ZETA_VS_CSV, "ζ {z} vs {zc}");
    }
}

/// Largest relative differences between the two-clock bag and the one-clock CSV.
const FREQ_VS_CSV: f64 = 2e-4;
const ZETA_VS_CSV: f64 = 0.03;

/// A gap in the wrench stream and a wrench starting after the IMU: the response samples
/// without an input are left out and counted in their window; a missing input topic, an
/// unknown encoding on it, a field not in it, --input-topic without --input or on a CSV: one
/// line each.
#[test]
fn wrench_topic_hostile() {
    let d = dir("input_topic_hostile");
    let rec = forced_chain(40.0, 7);
    let (imu, wrench, bag) = (d.join("imu.csv"), d.join("wrench.csv"), d.join("gap.mcap"));
    // IMU from sample 0, wrench from 0.3 ms: IMU sample 0 is before the wrench's span. The
    // wrench lacks samples 25000 … 25099: IMU samples 25000 … 25100 lie in the 101 ms gap
    // (over 2 wrench periods).
    write_imu(&imu, &rec, 0);
    write_wrench(&wrench, &rec, 0.3e-3, |k| !(25000..25100).contains(&k));
    let py = ros2_python();
    write_bag(&py, &imu, &bag, ["0", "0", "1"], Some(&wrench));
    let b = bag.to_str().unwrap();
    let args = [&["identify", b][..], &WRENCH_TOPIC].concat();
    let v = json_of(&run(&[
        &args[..],
        &["--json", "--window", "20", "--overlap", "0"],
    ]
    .concat()));
    let ws = v["windows"].as_array().unwrap();
    let counts: Vec<(f64, u64, &str)> = ws
        .iter()
        .map(|w| {
            (
                w["t_start_s"].as_f64().unwrap(),
                w["unmatched_samples"].as_u64().unwrap(),
                w["status"].as_str().unwrap(),
            )
        })
        .collect();
    println!("windows (start s, unmatched, status): {counts:?}");
    // The time origin is the IMU's first sample (the first message in the file).
    assert_eq!(
        counts[0].1, 1,
        "IMU sample 0, before the wrench: {counts:?}"
    );
    assert_eq!(counts[0].2, "gap");
    let at25: Vec<_> = counts
        .iter()
        .filter(|c| c.0 <= 25.0 && 25.1 < c.0 + 20.0)
        .collect();
    assert_eq!(at25.len(), 1, "{counts:?}");
    assert_eq!(at25[0].1, 101, "{counts:?}");
    assert_eq!(at25[0].2, "gap");
    assert_eq!(counts.iter().map(|c| c.1).sum::<u64>(), 102, "{counts:?}");
    // The text names the left-out samples (one window: 1 + 101).
    let o = run(&args);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("102 unmatched sample(s) left out"), "{text}");
    // A missing input topic.
    one_line(
        &run(&[
            "identify", b, "--topic", "/imu", "--input-topic", "/force", "--input", "fx",
        ]),
        "--input-topic /force: no message on that topic; topics in the file: /imu (sensor_msgs/msg/Imu), /pose (geometry_msgs/msg/PoseStamped), /wrench (geometry_msgs/msg/WrenchStamped)",
    );
    // A topic without the field (the poses).
    one_line(
        &run(&[
            "identify",
            b,
            "--topic",
            "/imu",
            "--input-topic",
            "/pose",
            "--input",
            "wrench.force.x",
        ]),
        "--input-topic /pose: no field `wrench.force.x` for --input",
    );
    one_line(
        &run(&["identify", b, "--input-topic", "/wrench"]),
        "--input-topic /wrench: name the input fields with --input",
    );
    one_line(
        &run(&[
            "identify",
            imu.to_str().unwrap(),
            "--input-topic",
            "/wrench",
            "--input",
            "fx",
        ]),
        "a CSV recording has no topics",
    );
    // An unknown encoding on the input topic.
    let odd = d.join("odd.mcap");
    let script = "import sys\nfrom mcap.writer import Writer\nw = Writer(open(sys.argv[1], 'wb'))\nw.start()\ns = w.register_schema(name='my/Force', encoding='protobuf', data=b'x')\nc = w.register_channel(topic='/wrench', message_encoding='protobuf', schema_id=s)\nw.add_message(channel_id=c, log_time=1, data=b'1', publish_time=1)\nw.finish()\n";
    let st = std::process::Command::new(&py)
        .args(["-c", script, odd.to_str().unwrap()])
        .status()
        .unwrap();
    assert!(st.success());
    one_line(
        &run(&[
            "identify",
            odd.to_str().unwrap(),
            "--input-topic",
            "/wrench",
            "--input",
            "force.x",
        ]),
        "topic /wrench: message encoding `protobuf` (schema `my/Force`) is not decoded",
    );
}
