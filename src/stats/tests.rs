use super::*;

fn naive(v: &[u64], q: f64) -> u64 {
    let mut s = v.to_vec();
    s.sort_unstable();
    percentile(&s, q)
}

#[test]
fn percentile_is_nearest_rank() {
    assert_eq!(percentile(&[], 0.5), 0);
    assert_eq!(percentile(&[7], 0.99), 7);
    assert_eq!(percentile(&[1, 2, 3, 4], 0.5), 3); // round(1.5) = 2
    assert_eq!(percentile(&[1, 2, 3, 4], 1.0), 4);
    assert_eq!(percentile(&[1, 2, 3, 4], 0.0), 1);
}

#[test]
fn status_histogram_counts_and_names() {
    let mut h = StatusHistogram::default();
    h.record(StatusCode::Ok);
    h.record(StatusCode::Ok);
    h.record(StatusCode::OutsideWorkspace);
    h.record_wire(1000);
    let mut g = StatusHistogram::default();
    g.record(StatusCode::OutsideWorkspace);
    h.merge(&g);
    assert_eq!(h.total(), 5);
    assert_eq!(h.count(StatusCode::OutsideWorkspace), 2);
    assert_eq!(h.counts()[STATUS_SLOTS - 1], 1);
    assert!(
        h.summary().starts_with("ok 2, outside_workspace 2"),
        "{}",
        h.summary()
    );
    assert!(!h.summary_not_ok().contains("ok 2"));
    assert_eq!(StatusHistogram::default().summary_not_ok(), "");
}

#[test]
fn percentiles_match_sorting() {
    let mut x: u64 = 12345;
    for n in [1usize, 2, 3, 10, 999, 1000, 1001, 5000] {
        let v: Vec<u64> = (0..n)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                x >> 40
            })
            .collect();
        let p = Percentiles::of(&mut v.clone());
        assert_eq!(p.count, n);
        assert_eq!(p.p50_ns, naive(&v, 0.5), "n = {n}");
        assert_eq!(p.p99_ns, naive(&v, 0.99), "n = {n}");
        assert_eq!(p.p999_ns, naive(&v, 0.999), "n = {n}");
        assert_eq!(p.max_ns, *v.iter().max().unwrap(), "n = {n}");
    }
    assert_eq!(Percentiles::of(&mut []), Percentiles::default());
}

#[test]
fn ring_keeps_the_most_recent() {
    let mut r = Ring::new(4);
    assert!(r.is_empty());
    for v in 1..=10 {
        r.push(v);
    }
    assert_eq!(r.len(), 4);
    let p = r.percentiles();
    assert_eq!((p.count, p.max_ns), (4, 10));
    assert_eq!(p.p50_ns, naive(&[7, 8, 9, 10], 0.5));
    r.clear();
    r.push(3);
    assert_eq!(r.percentiles().max_ns, 3);
}

#[test]
fn sample_log_never_grows() {
    let mut l = SampleLog::with_capacity(3);
    for v in 0..5 {
        l.push(v);
    }
    assert_eq!((l.len(), l.dropped()), (3, 2));
    assert_eq!(l.samples(), &[0, 1, 2]);
}

/// A sender's first message at 0, the later ones of the simple cases 1 s later (a budget
/// of 10⁷ poses, larger than any gap they make).
const NOW: u64 = 0;
const SEC: u64 = 1_000_000_000;

#[test]
fn sequence_gaps_in_order_count_nothing() {
    let mut g = SequenceGaps::<u32, 4>::default();
    for seq in 1..=1000 {
        assert_eq!(g.record(7, seq, NOW), 0);
    }
    assert_eq!((g.lost(), g.resets()), (0, 0));
}

#[test]
fn sequence_gaps_count_the_missing_sequences() {
    let mut g = SequenceGaps::<u32, 4>::default();
    assert_eq!(
        g.record(7, 5, NOW),
        0,
        "a sender's first sequence counts nothing"
    );
    assert_eq!(g.record(7, 6, SEC), 0);
    assert_eq!(g.record(7, 10, SEC), 3, "7, 8, 9 never received");
    assert_eq!(g.record(7, 11, SEC), 0);
    assert_eq!(g.record(7, 1011, SEC), 999);
    assert_eq!(g.lost(), 1002);
}

#[test]
fn sequence_gaps_duplicates_and_steps_back_count_nothing() {
    let mut g = SequenceGaps::<u32, 4>::default();
    for seq in [1, 2, 2, 3, 1, 2, 3, 4] {
        g.record(7, seq, NOW);
    }
    assert_eq!(g.lost(), 0, "a duplicate or a step back is no loss");
    assert_eq!(g.resets(), 2);
    // Out of order: 4 missing at 5, then 4 late: it re-bases, and 5 follows it.
    let mut g = SequenceGaps::<u32, 4>::default();
    for seq in [1, 2, 3, 5, 4, 5, 6] {
        g.record(7, seq, NOW);
    }
    assert_eq!(g.lost(), 1);
}

#[test]
fn sequence_gaps_a_restart_is_no_huge_gap() {
    // Same key, counter back to 1 after a long run: nothing, and the next gap is measured
    // from the new base, not from the old one.
    let mut g = SequenceGaps::<u32, 4>::default();
    g.record(7, 1_000_000, NOW);
    assert_eq!(g.record(7, 1, SEC), 0);
    assert_eq!(g.record(7, 2, SEC), 0);
    assert_eq!(g.record(7, 4, SEC), 1);
    assert_eq!(g.lost(), 1);
    // A restarted sender is a new key: a large first sequence is not compared with the
    // old sender's, nor is a small one.
    let mut g = SequenceGaps::<u32, 4>::default();
    g.record(1, 10, NOW);
    assert_eq!(
        g.record(2, u64::MAX - 1, NOW),
        0,
        "new sender, large first sequence"
    );
    assert_eq!(g.record(2, u64::MAX, SEC), 0);
    assert_eq!(g.record(3, 1, NOW), 0);
    assert_eq!(
        g.record(1, 11, SEC),
        0,
        "each sender against its own sequence"
    );
    assert_eq!(g.record(3, 3, SEC), 1);
    assert_eq!(g.lost(), 1);
}

/// A hostile sender (sequences 1, 2⁶³, 1, …, u64::MAX, 0, random) counts resets, never
/// a wrap-around loss (before: "overwritten poses 9223372036854775802"), and leaves an
/// honest sender's count exact over 10⁵ messages: received + lost = the sequences it sent
/// from its first received one on, counted independently by the sender loop.
#[test]
fn sequence_gaps_hostile_sequences_leave_another_senders_count_exact() {
    let mut g = SequenceGaps::<u32, 4>::default();
    let (mut received, mut first) = (0u64, None);
    let mut honest_seq = 0u64;
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut hostile_lost = 0u64;
    for i in 0..100_000u64 {
        // 2 µs per round: the honest sender's burst of at most 20 is 10⁷ per second, the
        // budget's rate.
        let now = i * 2_000;
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        let h = match i % 6 {
            0 | 2 => 1,
            1 => 1 << 63,
            3 => u64::MAX,
            4 => 0,
            _ => rng,
        };
        hostile_lost += g.record(9, h, now);
        // Honest: sends 1 to 20 poses; the queue lets the last 1 to 3 of them through.
        let burst = 1 + rng % 20;
        honest_seq += burst;
        for k in (0..burst.min(1 + (rng >> 32) % 3)).rev() {
            let seq = honest_seq - k;
            first.get_or_insert(seq);
            let _ = g.record(7, seq, now);
            received += 1;
        }
    }
    let (lost, resets) = g.of(7).unwrap();
    assert_eq!(resets, 0, "an honest sender never resets");
    let sent_from_first = honest_seq - first.unwrap() + 1;
    assert_eq!(received + lost, sent_from_first);
    let (h_lost, h_resets) = g.of(9).unwrap();
    assert_eq!(h_lost, hostile_lost);
    assert!(h_resets > 60_000, "{h_resets}");
    // Only the random forward steps within the budget count: at most the slack and the
    // rate over the 0.2 s of the run.
    assert!(
        h_lost <= SEQUENCE_QUEUE_SLACK + 200_000_000 / 100,
        "{h_lost}"
    );
    assert_eq!(g.lost(), lost + h_lost);
    assert_eq!(g.resets(), h_resets);
    // The reported case: 1, 2⁶³, 1 is two resets and no loss.
    let mut g = SequenceGaps::<u32, 4>::default();
    for seq in [1, 1 << 63, 1] {
        assert_eq!(g.record(3, seq, NOW), 0);
    }
    assert_eq!((g.lost(), g.resets()), (0, 2));
    // Within the window a step is a loss; one past it is a reset.
    assert_eq!(
        g.record(3, 2 + SEQUENCE_GAP_WINDOW, SEC),
        SEQUENCE_GAP_WINDOW
    );
    assert_eq!(g.record(3, 3 + 2 * SEQUENCE_GAP_WINDOW + 1, SEC), 0);
    assert_eq!(g.resets(), 3);
}

/// A sender stepping its sequence forward by the window on every message (1 µs apart)
/// counted 2²⁰ lost poses per message, 10¹¹ over 10⁵ messages, in the service's total;
/// now its losses stay within its budget (16 + 10⁷ per second since its first message:
/// ~10⁶ here), the steps past it are resets, and another sender's count is untouched.
#[test]
fn sequence_gaps_one_sender_cannot_inflate_the_total() {
    let mut g = SequenceGaps::<u32, 4>::default();
    let (mut seq, mut honest) = (0u64, 0u64);
    for i in 0..100_000u64 {
        let now = i * 1_000;
        seq += SEQUENCE_GAP_WINDOW + 1;
        g.record(9, seq, now);
        honest += 1;
        assert_eq!(g.record(7, honest, now), 0);
    }
    let elapsed_ns = 99_999 * 1_000;
    let (lost, resets) = g.of(9).unwrap();
    assert!(lost <= SEQUENCE_QUEUE_SLACK + elapsed_ns / 100, "{lost}");
    assert!(resets > 99_000, "{resets}");
    assert_eq!(g.of(7), Some((0, 0)));
    assert_eq!(g.lost(), lost);
}

#[test]
fn sequence_gaps_evict_the_least_recent_sender() {
    let mut g = SequenceGaps::<u32, 2>::default();
    g.record(1, 1, NOW);
    g.record(2, 1, NOW);
    g.record(1, 2, NOW);
    g.record(3, 100, NOW); // replaces sender 2, heard from least recently
    assert_eq!(g.record(1, 3, NOW), 0, "sender 1 is still tracked");
    assert_eq!(
        g.record(2, 50, NOW),
        0,
        "sender 2 starts over: a first sequence"
    );
    assert_eq!(g.lost(), 0);
}

const MS: u64 = 1_000_000;

#[test]
fn gap_detector_reports_an_outage_once_at_start_and_at_end() {
    let mut d = GapDetector::new(100 * MS);
    assert_eq!(
        d.poll(10_000 * MS),
        None,
        "nothing before the first message"
    );
    for t in 0..1000 {
        assert_eq!(d.on_message(t * MS), None);
        assert_eq!(d.poll(t * MS + MS / 2), None);
    }
    // Last message at 999 ms; silence until 4300 ms.
    assert_eq!(d.poll(1098 * MS), None);
    assert_eq!(
        d.poll(1099 * MS),
        Some(GapEvent::Started {
            silent_ns: 100 * MS
        })
    );
    assert!(d.in_outage());
    for t in 1100..4300 {
        assert_eq!(d.poll(t * MS), None, "one line per outage start");
    }
    assert_eq!(
        d.on_message(4300 * MS),
        Some(GapEvent::Ended {
            duration_ns: 3301 * MS
        })
    );
    assert_eq!(d.on_message(4301 * MS), None);
    // A second, shorter one that no poll saw start.
    assert_eq!(
        d.on_message(4501 * MS),
        Some(GapEvent::Ended {
            duration_ns: 200 * MS
        })
    );
    // Jitter below the threshold is no outage.
    assert_eq!(d.on_message(4600 * MS), None);
    d.finish(4650 * MS);
    assert_eq!(d.outages(), 2);
    assert_eq!(d.longest_ns(), 3301 * MS);
    assert_eq!(d.total_ns(), 3501 * MS);
    // An outage still going on at the end is counted up to then.
    d.poll(4800 * MS);
    d.finish(5000 * MS);
    assert_eq!((d.outages(), d.longest_ns()), (3, 3301 * MS));
    assert_eq!(d.total_ns(), 3501 * MS + 350 * MS);
}
