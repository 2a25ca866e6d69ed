//! The phases of one cycle's end-effector work within the budget: a warm cycle of the
//! watched modes, a scan (started, or continued from an earlier cycle), and the warm cycle
//! that certifies what a scan found over several cycles.

use super::member::Member;
use super::scan::{self, ScanState, ScanStep};
use super::{
    EeTracker, RescanReason, CERT_MARGIN, PHASES_PER_CYCLE, P_ADD, RESCAN_WINDOW,
    WEAK_RESCAN_CYCLES,
};
use crate::modal::first_mode::TautFinder;
use crate::modal::{ModalError, Root};

impl EeTracker {
    /// Track, scan, or continue a scan, until an answer or the budget's end.
    pub(super) fn ee_phases(
        &mut self,
        f: &mut TautFinder<'_>,
        first: &Root,
        thr: f64,
    ) -> Result<Option<Root>, ModalError> {
        for _ in 0..PHASES_PER_CYCLE {
            if self.scan.is_none() {
                let reason = if self.n_members > 0 {
                    match self.track_watched(f, thr) {
                        Ok(r) => return Ok(Some(r)),
                        Err(_) if f.exhausted() => return Ok(None),
                        Err(why) => why,
                    }
                } else {
                    RescanReason::Cold
                };
                self.counts.record(reason);
                self.start_scan(f, first, reason);
            }
            let Some((r, resumed, window)) = self.run_scan(f) else {
                return Ok(None);
            };
            if let Some(out) = self.scan_done(f, r, resumed, window, thr) {
                return out;
            }
        }
        Ok(None)
    }

    /// Continue the scan in progress, recording what it finds; None when the budget ran out
    /// (it goes on next cycle), else its result, whether it ran over earlier cycles, and
    /// whether it started from a window.
    fn run_scan(
        &mut self,
        f: &mut TautFinder<'_>,
    ) -> Option<(Result<Root, ModalError>, bool, bool)> {
        let resumed = self.scan.is_some_and(|s| s.resumed > 0);
        let window = self.scan.is_some_and(|s| s.window);
        self.recording = true;
        let step = self.scan_step(f);
        self.recording = false;
        match step {
            ScanStep::Paused => {
                if let Some(s) = self.scan.as_mut() {
                    s.resumed += 1;
                    if s.resumed == 1 {
                        self.counts.continued_scans += 1;
                    }
                }
                None
            }
            ScanStep::Done(r) => Some((r, resumed, window)),
        }
    }

    /// What a finished scan's result `r` comes to: Some(the cycle's outcome), or None for
    /// another phase (certify what a scan found over several cycles; scan from zero after a
    /// window that did not certify).
    fn scan_done(
        &mut self,
        f: &TautFinder<'_>,
        r: Result<Root, ModalError>,
        resumed: bool,
        window: bool,
        thr: f64,
    ) -> Option<Result<Option<Root>, ModalError>> {
        let reached = matches!(r, Ok(ref x) if x.ee_participation >= thr);
        if resumed && reached {
            // Found over several cycles: certify at this cycle's pose (a warm cycle of the
            // watched modes) before anything is reported.
            return None;
        }
        if window {
            // Certified, this is the answer; else scan from zero.
            return match r {
                Ok(r) if reached && self.unwatched_bound(r.lambda) + CERT_MARGIN < thr => {
                    Some(Ok(Some(r)))
                }
                _ => {
                    self.n_members = 0;
                    None
                }
            };
        }
        let r = match r {
            Ok(r) => r,
            Err(e) => {
                self.n_members = 0;
                return Some(Err(e));
            }
        };
        if r.ee_participation < thr {
            // Weak: watch only this mode until the next full scan.
            let (a, b) = f.view.p.pole_interval(r.lambda);
            self.members[0] = Member::new(r.lambda, r.ee_participation, 0, 0, a, b);
            self.n_members = 1;
            self.ee_skip = WEAK_RESCAN_CYCLES;
        }
        Some(Ok(Some(r)))
    }

    /// Start a scan for `reason`: from 10 % below the lowest watched mode after a failed
    /// warm cycle (the watched modes are those the participation moves among; the modes
    /// below stay unwatched and covered by the bound), from zero otherwise.
    fn start_scan(&mut self, f: &TautFinder<'_>, first: &Root, reason: RescanReason) {
        let window = if reason != RescanReason::Cold && self.n_members > 0 {
            RESCAN_WINDOW * self.members[0].lambda
        } else {
            0.0
        };
        self.n_members = 0;
        if window > 0.0 {
            if first.ee_participation >= P_ADD && first.lambda < window {
                self.watch_first(f, first);
            }
            let skip = window * (1.0 - scan::WINDOW_EDGE);
            self.scan = Some(ScanState::new(f.view.p, window, skip, f64::INFINITY, true));
        } else {
            if first.ee_participation >= P_ADD {
                self.watch_first(f, first);
            }
            self.scan = Some(ScanState::new(
                f.view.p,
                0.0,
                first.lambda,
                f64::INFINITY,
                false,
            ));
        }
    }

    /// Mark every watched mode as not followed at this cycle's pose.
    pub(super) fn age_members(&mut self) {
        for m in &mut self.members[..self.n_members] {
            m.age += 1;
        }
    }
}
