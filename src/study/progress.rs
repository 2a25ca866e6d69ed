//! The progress bar of a long sweep: points done, percentage and ETA on stderr (indicatif).
//!
//! Drawn only when it helps a person watching: stderr is a terminal, and the sweep has
//! already run for [`SHOW_AFTER`] (a sweep that ends sooner prints nothing). When stderr
//! is a file or a pipe nothing is drawn at all, so logs and captured output hold only the
//! command's summary. The bar is cleared when the sweep ends.
//!
//! The bar is the crate's `progress` feature (the command line turns it on); without it
//! nothing is drawn and the crate does not build indicatif.

#[cfg(feature = "progress")]
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
/// Without the `progress` feature there is no bar: a type with no value.
#[cfg(not(feature = "progress"))]
type ProgressBar = std::convert::Infallible;
#[cfg(feature = "progress")]
use std::io::IsTerminal;
use std::sync::atomic::AtomicBool;
#[cfg(feature = "progress")]
use std::sync::atomic::Ordering;
use std::time::Duration;

/// A sweep shorter than this shows no bar: it would only flicker.
pub const SHOW_AFTER: Duration = Duration::from_secs(1);
#[cfg(feature = "progress")]
/// Most redraws a second (indicatif's default is 20; 4 keep a shared terminal quiet).
const REFRESH_PER_S: u8 = 4;
#[cfg(feature = "progress")]
/// The bar's layout: label, bar, units done of total (`{msg}`: their name), percentage, ETA.
const TEMPLATE: &str = "{prefix}: [{bar:30}] {pos}/{len} {msg} {percent:>3}% ETA {eta}";

/// A progress bar that stays hidden until [`SHOW_AFTER`] has passed on a terminal.
#[derive(Debug)]
pub struct Progress {
    /// None: no bar (not asked for, or stderr is not a terminal).
    bar: Option<ProgressBar>,
    shown: AtomicBool,
}

impl Progress {
    /// A bar labelled `label` over `total` points; none when `label` is None or stderr is
    /// not a terminal.
    pub fn new(label: Option<&str>, total: usize) -> Progress {
        Progress::counting(label, total, "points")
    }

    /// A bar labelled `label` over `total` units named `unit` (`frequencies`, `samples`).
    pub fn counting(label: Option<&str>, total: usize, unit: &'static str) -> Progress {
        #[cfg(not(feature = "progress"))]
        let bar = {
            let _ = (label, total, unit);
            None
        };
        #[cfg(feature = "progress")]
        let bar = label.filter(|_| std::io::stderr().is_terminal()).map(|l| {
            let b = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::hidden());
            if let Ok(style) = ProgressStyle::with_template(TEMPLATE) {
                b.set_style(style.progress_chars("=> "));
            }
            b.set_prefix(l.to_string());
            b.set_message(unit);
            b
        });
        Progress {
            bar,
            shown: AtomicBool::new(false),
        }
    }

    /// `n` more points done (from any worker).
    pub fn advance(&self, n: usize) {
        let Some(b) = &self.bar else { return };
        #[cfg(not(feature = "progress"))]
        let _ = (n, *b, &self.shown);
        #[cfg(feature = "progress")]
        {
            b.inc(n as u64);
            if b.elapsed() >= SHOW_AFTER && !self.shown.swap(true, Ordering::Relaxed) {
                b.set_draw_target(ProgressDrawTarget::stderr_with_hz(REFRESH_PER_S));
            }
        }
    }

    /// The sweep is over: clear the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            #[cfg(not(feature = "progress"))]
            let _ = *b;
            #[cfg(feature = "progress")]
            b.finish_and_clear();
        }
    }
}
