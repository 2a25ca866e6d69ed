//! `replay` in bounded memory and time: a long recording streamed (peak resident memory of the
//! process measured by the kernel, `wait4`'s `ru_maxrss`), a chunk claiming 2.5 GB refused with
//! one line, a FIFO and `/dev/zero` refused at once, a pause of 2⁶⁴ ns shortened to
//! `--max-gap-s`, and SIGTERM obeyed within a sleep slice.
//!
//! The recordings are written here with the `mcap` crate, with the monitor's schemas and JSON
//! records (`cablevib_monitor::encode`): one pose and its estimate per millisecond (or the
//! step given), LZ4 chunks of 256 KiB as the monitor writes them.

use std::collections::BTreeMap;
use std::io::BufWriter;

use cablevib_monitor::encode::{self, PoseRecord};

use super::*;

/// Writes a monitor-like recording of `n` poses, each followed by its estimate; pose `k` at
/// timestamp `ts(k)` ns.
fn write_recording(path: &Path, n: u64, ts: impl Fn(u64) -> u64) {
    let f = BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Lz4))
        .chunk_size(Some(256 * 1024))
        .create(f)
        .unwrap();
    let json = encode::JSON_SCHEMA_ENCODING;
    let pose_schema = w
        .add_schema(encode::SCHEMA_POSE, json, encode::pose_schema().as_bytes())
        .unwrap();
    let est_schema = w
        .add_schema(
            encode::SCHEMA_ESTIMATE,
            json,
            encode::estimate_schema().as_bytes(),
        )
        .unwrap();
    let none = BTreeMap::new();
    let pose_ch = w
        .add_channel(pose_schema, "/cablevib/pose", "json", &none)
        .unwrap();
    let est_ch = w
        .add_channel(est_schema, "/cablevib/estimate", "json", &none)
        .unwrap();
    let scene = Scene::default_scene();
    let trajectory = Trajectory::circle(&scene, CIRCLE_PERIOD_S).unwrap();
    let mut e = EstimateSample::with_status(cablevib_ipc::StatusCode::Ok);
    e.set_tensions(&[100.0; 8]).unwrap();
    e.set_stiffness(3, &[1e5; 9]).unwrap();
    e.f1_hz = 9.0;
    for k in 1..=n {
        let t = ts(k);
        let p = trajectory.position_at((k % 4000) as f64 * 1e-3).unwrap();
        let pose = PoseSample::new(k, t, [p.x, p.y, p.z], IDENTITY_QUATERNION);
        let header = |channel_id, sequence| mcap::records::MessageHeader {
            channel_id,
            sequence,
            log_time: t,
            publish_time: t,
        };
        let data = serde_json::to_vec(&PoseRecord::new(&pose)).unwrap();
        w.write_to_known_channel(&header(pose_ch, k as u32), &data)
            .unwrap();
        e.sequence = k;
        e.pose_sequence = k;
        e.pose_timestamp_ns = t;
        e.publish_timestamp_ns = t.saturating_add(50_000);
        let data = serde_json::to_vec(&EstimateRecord::new(&e, f64::NAN)).unwrap();
        w.write_to_known_channel(&header(est_ch, k as u32), &data)
            .unwrap();
    }
    w.finish().unwrap();
}

/// Runs `cablevib replay ARGS`; returns (exit code, stdout, stderr, peak resident set of the
/// process in bytes). Fails the test past `limit`. The child is reaped by `wait4` (which gives
/// its resource usage), not by `Child::wait`.
#[allow(clippy::zombie_processes)]
fn replay_process(args: &[&str], limit: Duration) -> (i32, String, String, u64) {
    let child = Command::new(BIN)
        .arg("replay")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id() as libc::pid_t;
    let (mut out, mut err) = (child.stdout.unwrap(), child.stderr.unwrap());
    let read_out = std::thread::spawn(move || std::io::read_to_string(&mut out).unwrap());
    let read_err = std::thread::spawn(move || std::io::read_to_string(&mut err).unwrap());
    let start = Instant::now();
    loop {
        let mut status = 0;
        // SAFETY: an all-zero rusage is valid; wait4 on our own child's pid, not yet reaped.
        let mut usage: libc::rusage = unsafe { core::mem::zeroed() };
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            let code = if libc::WIFEXITED(status) {
                libc::WEXITSTATUS(status)
            } else {
                128 + libc::WTERMSIG(status)
            };
            // ru_maxrss is in KiB on Linux.
            let rss = usage.ru_maxrss as u64 * 1024;
            return (
                code,
                read_out.join().unwrap(),
                read_err.join().unwrap(),
                rss,
            );
        }
        if start.elapsed() > limit {
            // SAFETY: kill(2) on our own child.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            panic!("replay {args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A long recording is streamed: the replay's peak resident memory stays under 100 MB for
/// 2·10⁵ estimates (CABLEVIB_REPLAY_RSS_N sets another count; the measurement in
/// docs/security.md is this test at 10⁶). Before, the replay read the whole file and kept
/// every estimate as a JSON value, ≈ 4.4 KB each (≈ 880 MB here).
#[test]
fn replay_streams_a_long_recording_in_bounded_memory() {
    let n: u64 = std::env::var("CABLEVIB_REPLAY_RSS_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200_000);
    let file = scratch("long.mcap");
    // 20 µs apart at the recorded pace: the replay sends as fast as it can.
    write_recording(&file, n, |k| 1_000_000_000 + k * 20_000);
    let scene = Scene::default_scene();
    let instance = format!("cvmon_{}_long", std::process::id());
    let service = start_service(&instance, &scene);
    let (code, out, err, rss) = replay_process(
        &[file.to_str().unwrap(), "--instance", &instance],
        Duration::from_secs(600),
    );
    stop_service(service);
    let size = std::fs::metadata(&file).unwrap().len();
    println!(
        "{n} poses and estimates, {:.1} MB file: replay peak RSS {:.1} MB; {}",
        size as f64 / 1e6,
        rss as f64 / 1e6,
        out.trim()
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&format!("{n} poses")), "{out}");
    // The bound: iceoryx2's mappings and the process (≈ 20-30 MB), the reader's window of 8192
    // messages and one chunk, not a function of n.
    assert!(rss < 100_000_000, "peak RSS {rss} bytes for {n} estimates");
}

/// The byte offset of the first chunk record's `uncompressed_size` field (records after the
/// 8-byte magic: opcode, u64 length, body; a chunk's body starts with its start and end times).
fn first_chunk_uncompressed_size_at(bytes: &[u8]) -> usize {
    let mut at = 8;
    loop {
        let op = bytes[at];
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if op == 0x06 {
            return at + 9 + 16;
        }
        at += 9 + len;
    }
}

/// A chunk whose header claims 2.5 GB decompressed, and a FIFO and `/dev/zero` as the file:
/// each refused with one line, at once. Before, the replay read the whole file into memory
/// (`/dev/zero` grew to 2 GB, a FIFO blocked forever) and decompressed a chunk of any size.
#[test]
fn replay_refuses_huge_chunks_fifos_and_devices_with_one_line() {
    let file = scratch("huge-chunk.mcap");
    write_recording(&file, 100, |k| k * 1_000_000);
    let mut bytes = std::fs::read(&file).unwrap();
    let at = first_chunk_uncompressed_size_at(&bytes);
    bytes[at..at + 8].copy_from_slice(&2_500_000_000u64.to_le_bytes());
    std::fs::write(&file, &bytes).unwrap();
    let fifo = scratch("fifo.mcap");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo on a NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    for (f, says) in [
        (file.to_str().unwrap(), "over the limit of 67108864 bytes"),
        (
            fifo.to_str().unwrap(),
            "FIFO (named pipe), not a regular file",
        ),
        ("/dev/zero", "character device, not a regular file"),
    ] {
        let (code, _, err, rss) = replay_process(
            &[f, "--instance", "cvmon_nobody", "--wait-s", "1"],
            Duration::from_secs(60),
        );
        assert_ne!(code, 0, "{f}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{f}: {err}");
        assert!(err.contains(says), "{f}: {err}");
        assert!(rss < 100_000_000, "{f}: peak RSS {rss}");
    }
    let _ = std::fs::remove_file(&fifo);
}

/// A pause of 2⁶⁴ ns in a recording is shortened to `--max-gap-s` and counted; with a long
/// `--max-gap-s`, SIGTERM during the pause stops the replay within a sleep slice. Before, the
/// replay slept through the pause (584 years) and ignored SIGTERM while it slept.
#[test]
fn replay_shortens_long_pauses_and_stops_on_sigterm() {
    let file = scratch("pause.mcap");
    // Poses 1-10 a millisecond apart, then the clock jumps to 2⁶⁴ − 1 ns.
    write_recording(&file, 20, |k| {
        if k <= 10 {
            1_000_000_000 + k * 1_000_000
        } else {
            u64::MAX - 20 + k
        }
    });
    let scene = Scene::default_scene();
    let instance = format!("cvmon_{}_pause", std::process::id());
    let service = start_service(&instance, &scene);
    let args = [file.to_str().unwrap(), "--instance", &instance];
    let start = Instant::now();
    let (code, out, err, _) = replay_process(
        &[&args[..], &["--max-gap-s", "0.2"]].concat(),
        Duration::from_secs(60),
    );
    let took = start.elapsed();
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("20 poses") && out.contains("1 pauses shortened to 0.2 s"),
        "{out}"
    );
    println!("{} in {took:?}", out.trim());

    // An hour allowed: the replay sleeps in the pause until SIGTERM.
    let mut child = Command::new(BIN)
        .arg("replay")
        .args(args)
        .args(["--max-gap-s", "3600"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, libc::SIGTERM);
    let sent = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if sent.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("replay still sleeping 30 s after SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let stopped_in = sent.elapsed();
    let out = child.wait_with_output().unwrap();
    stop_service(service);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(status.success(), "{text}");
    assert!(text.contains("stopped by a signal"), "{text}");
    // The sleep slice is 20 ms; 5 s leaves room for a loaded machine.
    assert!(stopped_in < Duration::from_secs(5), "{stopped_in:?}");
    println!("SIGTERM in the pause: stopped after {stopped_in:?}");
}
