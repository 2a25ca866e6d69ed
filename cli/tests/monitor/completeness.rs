//! The monitor says how complete its record is: every estimate and pose the service's senders
//! published while it listened is either recorded or counted as lost, per channel, in the
//! summary and in the MCAP metadata record `cablevib.completeness`; checked against the
//! service's own count (its `ServerReport`) and the controller's, and against the sequence
//! numbers found in the file by the Python `mcap` reader (an independent count).

use super::*;

/// The Python reader's view of a recording: metadata records and, per channel, the messages
/// and the sequence range found in the file.
pub(crate) fn completeness_of(py: &Path, file: &Path) -> serde_json::Value {
    let out = Command::new(py)
        .arg(script("check_recording.py"))
        .args(["completeness", file.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "Python mcap reader: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

pub(crate) fn meta_u64(v: &serde_json::Value, key: &str) -> u64 {
    v["metadata"]["cablevib.completeness"][key]
        .as_str()
        .unwrap_or_else(|| panic!("no {key} in {v}"))
        .parse()
        .unwrap()
}

/// A monitor stopped (SIGSTOP) for 3.5 s during a 1 kHz run, longer than its queues of 2048
/// samples last: the estimates and poses it lost are counted exactly. Recorded + lost equals
/// the service's estimate count and the controller's pose count, the metadata's counts equal
/// what the Python reader finds in the file (messages, and the missing sequence numbers between
/// the first and the last), and the summary says the record is incomplete. Before the counts,
/// the monitor lost such messages silently and said "0 dropped".
#[test]
fn a_stalled_monitor_counts_what_it_lost_exactly() {
    let py = python();
    let scene = Scene::default_scene();
    let instance = format!("cvmon_{}_stall", std::process::id());
    let file = scratch("stall.mcap");
    let service = start_service(&instance, &scene);
    let (mut monitor, _, stdout) = start_monitor(&[
        "--instance",
        &instance,
        "--no-foxglove",
        "--record",
        file.to_str().unwrap(),
    ]);
    let controller = control_in_background(&instance, &scene, 7.0, 1000.0);
    std::thread::sleep(Duration::from_millis(1500));
    signal(&monitor, libc::SIGSTOP);
    std::thread::sleep(Duration::from_millis(3500));
    signal(&monitor, libc::SIGCONT);
    let run = controller.join().unwrap();
    signal(&monitor, libc::SIGTERM);
    let status = monitor.wait().unwrap();
    let lines = stdout.join().unwrap();
    let service_report = stop_service(service);
    assert!(status.success(), "{lines:?}");
    let summary = lines.join("\n");
    println!("{summary}");

    let c = completeness_of(&py, &file);
    let recorded = c["counted"]["estimate"]["messages"].as_u64().unwrap();
    let lost = meta_u64(&c, "estimate.lost_sequence_gap");
    // Exact: the monitor subscribed before the first estimate (first sequence 1) and read the
    // last one (the controller's final 300 ms drain leaves time for it).
    assert_eq!(meta_u64(&c, "estimate.recorded"), recorded);
    assert_eq!(meta_u64(&c, "estimate.first_sequence"), 1);
    assert_eq!(
        meta_u64(&c, "estimate.last_sequence"),
        service_report.cycles
    );
    assert_eq!(
        recorded + lost,
        service_report.cycles,
        "recorded {recorded} + lost {lost} vs the service's {} estimates",
        service_report.cycles
    );
    // Independent of the monitor's bookkeeping: the gaps in the recorded sequences.
    assert_eq!(c["counted"]["estimate"]["missing"].as_u64().unwrap(), lost);
    assert_eq!(meta_u64(&c, "estimate.dropped_queue"), 0);
    // 3.5 s at 1 kHz is more than the 2048-sample queue holds (when the service keeps up:
    // under load it estimates fewer poses, so only "some" is asserted).
    assert!(lost > 0, "the stall lost nothing? {summary}");

    let poses = c["counted"]["pose"]["messages"].as_u64().unwrap();
    let poses_lost = meta_u64(&c, "pose.lost_sequence_gap");
    assert_eq!(meta_u64(&c, "pose.recorded"), poses);
    assert_eq!(poses + poses_lost, run.poses.len() as u64);
    assert_eq!(
        c["counted"]["pose"]["missing"].as_u64().unwrap(),
        poses_lost
    );
    assert!(poses_lost > 0);
    assert_eq!(
        c["metadata"]["cablevib.completeness"]["complete"].as_str(),
        Some("false")
    );
    assert!(summary.contains("record INCOMPLETE"), "{summary}");
    assert!(
        summary.contains(&format!("{recorded} recorded, {lost} lost (sequence gaps)")),
        "{summary}"
    );
    println!(
        "service {} estimates: {recorded} recorded + {lost} lost; controller {} poses: {poses} \
         recorded + {poses_lost} lost",
        service_report.cycles,
        run.poses.len()
    );
}
