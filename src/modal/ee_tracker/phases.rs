//! The phases of one cycle's end-effector work within the budget: a warm cycle of the
//! watched modes, a scan (started, or continued from an earlier cycle), and the warm cycle
//! that certifies what a scan found over several cycles.

use super::member::Member;
use super::scan::{self, ScanState, ScanStep};
use super::track::track_root;
use super::{
    EeTracker, RescanReason, CERT_MARGIN, PHASES_PER_CYCLE, P_ADD, P_STRONG, RECORD_ABOVE,
    RESCAN_WINDOW, WEAK_RESCAN_CYCLES,
};
use crate::modal::engine::Condensed;
use crate::modal::first_mode::RootFinder;
use crate::modal::{ModalError, Root};

/// Where the count alone shows the poles, a window rescan starts below the watched modes
/// whose participation changed by at least this since they were found.
const WINDOW_CHANGE: f64 = 0.05;

impl EeTracker {
    /// Track, scan, or continue a scan, until an answer or the budget's end.
    pub(super) fn ee_phases<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        first: &Root,
        thr: f64,
    ) -> Result<Option<Root>, ModalError> {
        for _ in 0..PHASES_PER_CYCLE {
            if let Some(out) = self.certify_mid_sweep(f, thr) {
                return out;
            }
            if self.scan.is_none() {
                let reason = if self.n_members > 0 {
                    match self.track_watched(f, thr) {
                        Ok(r) => {
                            self.window_pending = false;
                            return Ok(Some(r));
                        }
                        Err(RescanReason::Starved) => return Ok(None),
                        Err(_) if f.exhausted() => return Ok(None),
                        Err(why) => why,
                    }
                } else {
                    RescanReason::Cold
                };
                self.counts.record(reason);
                self.start_scan(f, first, reason);
            }
            let Some((r, resumed, window, deferred)) = self.run_scan(f) else {
                return Ok(None);
            };
            if let Some(out) = self.scan_done(f, r, (resumed, window, deferred), thr) {
                return out;
            }
        }
        Ok(None)
    }

    /// A window sweep by the count that found its answer in an earlier cycle
    /// (`ScanState::cert_next`): a warm cycle of the watched modes at this cycle's pose;
    /// Some(its answer) when it certifies (the sweep is dropped), Some(Ok(None)) when the
    /// budget ran out, None otherwise (the sweep goes on, recording past the answer).
    fn certify_mid_sweep<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        thr: f64,
    ) -> Option<Result<Option<Root>, ModalError>> {
        let s = self.scan.as_mut().filter(|s| s.cert_next)?;
        s.cert_next = false;
        match self.track_watched(f, thr) {
            Ok(a) => {
                self.scan = None;
                self.window_pending = false;
                Some(Ok(Some(a)))
            }
            Err(RescanReason::Starved) => Some(Ok(None)),
            Err(_) if f.exhausted() => Some(Ok(None)),
            Err(_) => None,
        }
    }

    /// Continue the scan in progress, recording what it finds; None when the budget ran out
    /// (it goes on next cycle), else its result, whether it ran over earlier cycles, whether
    /// it started from a window, and whether it is the recording of a scan that answered
    /// at an earlier call (`ScanState::defer`).
    fn run_scan<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
    ) -> Option<(Result<Root, ModalError>, bool, bool, bool)> {
        let resumed = self.scan.is_some_and(|s| s.resumed > 0);
        let window = self.scan.is_some_and(|s| s.window);
        let deferred = self.scan.is_some_and(|s| s.deferred);
        // A sweep that skipped a mode needs the certificate, as a window does.
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
            ScanStep::Done(r) => Some((r, resumed, window || self.skipped, deferred)),
        }
    }

    /// What a finished scan's result `r` comes to: Some(the cycle's outcome), or None for
    /// another phase (certify what a scan found over several cycles; scan from zero after a
    /// window that did not certify). `how`: whether the scan ran over earlier cycles,
    /// started from a window, and is a deferred recording (`run_scan`).
    fn scan_done<P: Condensed>(
        &mut self,
        f: &mut RootFinder<'_, P>,
        r: Result<Root, ModalError>,
        (resumed, window, deferred): (bool, bool, bool),
        thr: f64,
    ) -> Option<Result<Option<Root>, ModalError>> {
        let reached = matches!(r, Ok(ref x) if x.ee_participation >= thr);
        if window && !f.view.poles_known() {
            // A window rescan where the count alone shows the poles: its answer stands
            // only once a warm cycle of what it watched certifies it at this cycle's pose
            // (the modes below the window were not read again); else scan from zero.
            if reached {
                match self.track_watched(f, thr) {
                    Ok(a) => {
                        self.window_pending = false;
                        return Some(Ok(Some(a)));
                    }
                    // The budget ran out: the warm cycle is tried again next cycle.
                    Err(RescanReason::Starved) => return Some(Ok(None)),
                    Err(_) if f.exhausted() => return Some(Ok(None)),
                    Err(_) => {}
                }
            }
            self.n_members = 0;
            return None;
        }
        if resumed && reached && (f.view.poles_known() || deferred) {
            // Found over several cycles (or answered at an earlier call, recorded past the
            // answer now): certify at this cycle's pose (a warm cycle of the watched modes,
            // else a rescan) before anything is reported.
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
        if !f.view.poles_known() {
            return self.start_sweep(f, first, reason);
        }
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
            self.scan = Some(ScanState::new(&f.view, window, skip, f64::INFINITY, true));
        } else {
            if first.ee_participation >= P_ADD {
                self.watch_first(f, first);
            }
            self.scan = Some(ScanState::from_zero(&f.view, first.lambda));
        }
    }

    /// [`Self::start_scan`] where the count alone shows the poles (the scan is a sweep of
    /// the spectrum, tens of evaluations a mode): after a failed warm cycle, a sweep from
    /// 10 % below the last answer or the lowest watched mode whose participation changed by
    /// [`WINDOW_CHANGE`] since it was found, whichever is lower (the participation the
    /// certificate misses left those modes for their neighbours; without either, the
    /// lowest watched mode with participation ≥ [`P_STRONG`]) up to at least
    /// [`RECORD_ABOVE`] times the highest watched one, the watched modes below it kept
    /// (followed again by the warm cycle that must certify its answer); tried once until a
    /// warm cycle certifies, then from zero.
    fn start_sweep<P: Condensed>(
        &mut self,
        f: &RootFinder<'_, P>,
        first: &Root,
        reason: RescanReason,
    ) {
        let n = self.n_members;
        let window = if reason != RescanReason::Cold && n > 0 && !self.window_pending {
            let ms = &self.members[..n];
            let thr = f.params.ee_participation_min;
            let answer = ms.iter().find(|m| m.p >= thr).map(|m| m.lambda);
            let changed = ms
                .iter()
                .find(|m| (m.p - m.p_ref).abs() >= WINDOW_CHANGE)
                .map(|m| m.lambda);
            let low = match (answer, changed) {
                (Some(a), Some(c)) => a.min(c),
                (Some(x), None) | (None, Some(x)) => x,
                (None, None) => ms.iter().find(|m| m.p >= P_STRONG).unwrap_or(&ms[0]).lambda,
            };
            RESCAN_WINDOW * low
        } else {
            0.0
        };
        self.window_pending = window > 0.0;
        if window > 0.0 {
            let record_to = RECORD_ABOVE * self.members[n - 1].lambda;
            // Keep the watched modes below the window.
            let mut k = 0;
            for i in 0..n {
                if self.members[i].lambda < window {
                    self.members[k] = self.members[i];
                    k += 1;
                }
            }
            self.n_members = k;
            if first.ee_participation >= P_ADD && first.lambda < window {
                self.watch_first(f, first);
            }
            let skip = window * (1.0 - scan::WINDOW_EDGE);
            let mut st = ScanState::new(&f.view, window, skip, f64::INFINITY, true);
            st.record_to = record_to;
            self.scan = Some(st);
        } else {
            self.n_members = 0;
            if first.ee_participation >= P_ADD {
                self.watch_first(f, first);
            }
            let mut st = ScanState::from_zero(&f.view, first.lambda);
            // A cold start with no cycle budget (a study's point): answer first, record
            // past the answer if the next call is warm.
            st.defer = reason == RescanReason::Cold && f.budget == u32::MAX;
            self.scan = Some(st);
        }
    }

    /// Mark every watched mode as not followed at this cycle's pose.
    pub(super) fn age_members(&mut self) {
        for m in &mut self.members[..self.n_members] {
            m.age += 1;
        }
    }
}
