//! The iceoryx2 service (being written; see issue 4).
use clap::Args;

/// `cablevib serve` options.
#[derive(Debug, Args)]
pub struct ServeArgs {}
/// `cablevib demo` options.
#[derive(Debug, Args)]
pub struct DemoArgs {}
/// `cablevib bench-ipc` options.
#[derive(Debug, Args)]
pub struct BenchIpcArgs {}

/// Errors of the service.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// Not yet built.
    #[error("not implemented yet")]
    NotImplemented,
}
/// Run the service.
pub fn serve(_a: &ServeArgs, _allocations: fn() -> u64) -> Result<(), ServiceError> {
    Err(ServiceError::NotImplemented)
}
/// Run the demo.
pub fn demo(_a: &DemoArgs) -> Result<(), ServiceError> {
    Err(ServiceError::NotImplemented)
}
/// Measure IPC latency.
pub fn bench_ipc(_a: &BenchIpcArgs) -> Result<(), ServiceError> {
    Err(ServiceError::NotImplemented)
}
