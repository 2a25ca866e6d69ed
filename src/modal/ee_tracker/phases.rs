//! The phases of one cycle's end-effector work within the budget: a warm cycle of the
//! watched modes, a scan (started, or continued from an earlier cycle), and the warm cycle
//! that certifies what a scan found over several cycles.

use super::member::Member;
use super::scan::{self, ScanState, ScanStep};
use super::track::track_root;
use super::{
    EeTracker, RescanReason, CERT_MARGIN, PHASES_PER_CYCLE, P_ADD, RESCAN_WINDOW,
    WEAK_RESCAN_CYCLES,
};
use crate::modal::engine::Condensed;
use crate::modal::first_mode::RootFinder;
use crate::modal::{ModalError, Root};

impl EeTracker {
    /// Track, scan, or continue a scan, until an answer or the budget's end.
    pub(super) fn ee_phases<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
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
    fn run_scan<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
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
    fn scan_done<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        r: Result<Root, ModalError>,
        resumed: bool,
        window: bool,
        thr: f64,
    ) -> Option<Result<Option<Root>, ModalError>> {
        let reached = matches!(r, Ok(ref x) if x.ee_participation >= thr);
        if resumed && reached && f.view.poles_known() {
            // Found over several cycles: certify at this cycle's pose (a warm cycle of the
            // watched modes) before anything is reported.
            return None;
        }
        if let (true, true, Ok(ans)) = (resumed, reached, &r) {
            // Where the count alone shows the poles, the scan read every mode below the
            // answer (at the poses of the cycles it passed them in): the answer certified
            // at this cycle's pose by a warm cycle, or else followed to this pose.
            if let Ok(a) = self.track_watched(f, thr) {
                return Some(Ok(Some(a)));
            }
            return Some(Ok(track_root(f, ans.lambda, f.params.newton_accept)
                .filter(|t| t.root.ee_participation >= thr)
                .map(|t| t.root)));
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
            let (a, b) = f
                .view
                .pole_interval(r.lambda)
                .unwrap_or((0.0, f64::INFINITY));
            self.members[0] = Member::new(r.lambda, r.ee_participation, 0, 0, a, b);
            self.n_members = 1;
            self.ee_skip = WEAK_RESCAN_CYCLES;
        }
        Some(Ok(Some(r)))
    }

    /// Start a scan for `reason`: from 10 % below the lowest watched mode after a failed
    /// warm cycle (the watched modes are those the participation moves among; the modes
    /// below stay unwatched and covered by the bound), from zero otherwise.
    fn start_scan<P: Condensed>(
        &mut self,
        f: &RootFinder<'_, P>,
        first: &Root,
        reason: RescanReason,
    ) {
        // Where the count alone shows the poles a window scan costs what a scan from zero
        // does below the answer's neighbours, and its answer would need a certificate the
        // watched modes do not give: scan from zero.
        let window = if reason != RescanReason::Cold && self.n_members > 0 && f.view.poles_known() {
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
            self.scan = Some(ScanState::new(&f.view, window, skip, f64::INFINITY, true));
        } else {
            if first.ee_participation >= P_ADD {
                self.watch_first(f, first);
            }
            self.scan = Some(ScanState::from_zero(&f.view, first.lambda));
        }
    }

    /// Mark every watched mode as not followed at this cycle's pose.
    pub(super) fn age_members(&mut self) {
        for m in &mut self.members[..self.n_members] {
            m.age += 1;
        }
    }
}
