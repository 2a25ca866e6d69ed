//! [`ServiceError`], the errors of the service commands, and the parameters they name.
//!
//! A refused configuration value names its [`ServiceParam`] as the configuration field does
//! (`rate_hz`, `instance`); the command line renders the same error with its option names
//! ([`ServiceError::render`]).

use crate::estimator::BuildError;
use crate::hold::HoldError;
use crate::scene::SceneError;
use crate::trajectory::shaping::ShapingError;
use crate::trajectory::TrajectoryError;
use cablevib::study::{ParamError, ParamName};
use cablevib_ipc::InstanceError;

/// A parameter of the service commands, as their configurations name it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ServiceParam {
    /// How long the demo's replay publishes poses, s.
    Seconds,
    /// The demo's pose rate, Hz.
    RateHz,
    /// The required first natural frequency, Hz.
    RequiredHz,
    /// The f1 the demo's controller holds, Hz.
    HoldF1Hz,
    /// The demo's T_min schedule.
    TMinSchedule,
    /// The demo's per-estimate hold record (CSV).
    HoldCsv,
    /// The benchmark's timed samples.
    Samples,
    /// The shaper of the demo's replay.
    Shape,
    /// The instance name prefixing the service names.
    Instance,
}

impl ParamName for ServiceParam {
    fn name(self) -> &'static str {
        match self {
            ServiceParam::Seconds => "seconds",
            ServiceParam::RateHz => "rate_hz",
            ServiceParam::RequiredHz => "required_hz",
            ServiceParam::HoldF1Hz => "hold_f1_hz",
            ServiceParam::TMinSchedule => "t_min_schedule",
            ServiceParam::HoldCsv => "hold_csv",
            ServiceParam::Samples => "samples",
            ServiceParam::Shape => "shape",
            ServiceParam::Instance => "instance",
        }
    }
}

/// Errors of the service commands.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// Standard output could not be written.
    #[error(transparent)]
    Stdout(#[from] crate::output_file::StdoutError),
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The trajectory could not be made or read.
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    /// The estimator could not be built for the scene.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// A configuration value refused.
    #[error(transparent)]
    Param(#[from] ParamError<ServiceParam>),
    /// A bad hold parameter.
    #[error(transparent)]
    Hold(#[from] HoldError),
    /// A bad instance name.
    #[error(transparent)]
    Instance(#[from] InstanceError),
    /// A T_min schedule item that does not parse.
    #[error("T_min schedule item `{item}`: {reason}")]
    Schedule {
        /// The item as given.
        item: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The demo's shaper could not be built.
    #[error("{}", self.render(&ServiceParam::name))]
    Shape {
        /// The shaper.
        kind: &'static str,
        /// Why (in the message, not a source: the line is whole).
        reason: ShapingError,
    },
    /// The demo's hold record could not be written.
    #[error("{}", self.render(&ServiceParam::name))]
    HoldRecord {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        reason: String,
    },
    /// A name iceoryx2 refuses (service, node, attribute).
    #[error("{what}: {reason}")]
    Name {
        /// The name and what it names.
        what: String,
        /// Why.
        reason: String,
    },
    /// A thread could not be started.
    #[error("cannot start the {what} thread: {reason}")]
    Thread {
        /// Which thread.
        what: &'static str,
        /// The operating system's reason.
        reason: String,
    },
    /// The vibration tracker's parameters were refused.
    #[error("vibration tracker: {0}")]
    Tracker(#[from] cablevib::measured::ParamsError),
    /// The demo's synthetic accelerometer could not be set up (its simulation's pose,
    /// modal basis or path).
    #[error("accelerometer: {0}")]
    Accelerometer(String),
    /// The demo's service or controller stopped before the demo began.
    #[error("the service or the controller stopped before the demo began")]
    DemoNotStarted,
    /// A peer created a service with another message layout (another schema version).
    #[error("incompatible peer: {0}")]
    IncompatiblePeer(String),
    /// iceoryx2 refused an operation.
    #[error("iceoryx2: {context}: {reason}")]
    Ipc {
        /// What was being done.
        context: String,
        /// iceoryx2's error.
        reason: String,
    },
    /// An existing service was created (by another program) with other limits than cablevib
    /// creates it with; using it could admit impostors or drop messages.
    #[error("{}", self.render(&ServiceParam::name))]
    ServiceSettings {
        /// The iceoryx2 service name.
        service: String,
        /// The static setting that differs.
        setting: &'static str,
        /// Its value in the existing service.
        found: String,
        /// What cablevib needs.
        expected: String,
    },
    /// Another live cablevib service already serves this instance.
    #[error("{}", self.render(&ServiceParam::name))]
    AlreadyServing {
        /// The margin service both would serve.
        service: String,
    },
    /// SIGINT/SIGTERM arrived before the service was up.
    #[error("interrupted by a signal")]
    Interrupted,
    /// A thread of `demo` or `bench-ipc` panicked.
    #[error("the {0} thread panicked")]
    ThreadPanicked(&'static str),
    /// The other side did not answer in time.
    #[error("timed out: {0}")]
    Timeout(String),
}

impl ServiceError {
    /// The message with each parameter called `name(param)` (the command line passes its
    /// option names); the `Display` text uses [`ParamName::name`].
    pub fn render(&self, name: &dyn Fn(ServiceParam) -> &'static str) -> String {
        match self {
            ServiceError::Param(e) => e.render(name),
            ServiceError::Shape { kind, reason } => {
                format!("{} {kind}: {reason}", name(ServiceParam::Shape))
            }
            ServiceError::HoldRecord { path, reason } => {
                format!(
                    "{} {}: {reason}",
                    name(ServiceParam::HoldCsv),
                    path.display()
                )
            }
            ServiceError::ServiceSettings {
                service,
                setting,
                found,
                expected,
            } => format!(
                "service \"{service}\" exists with {setting} = {found}, expected {expected}; \
                 another program created it: stop that program, or use another {}",
                name(ServiceParam::Instance)
            ),
            ServiceError::AlreadyServing { service } => format!(
                "another cablevib service already serves \"{service}\"; stop it, or give this \
                 one another {}",
                name(ServiceParam::Instance)
            ),
            other => other.to_string(),
        }
    }
}
