//! The `cablevib` command-line tool. See `cablevib --help`.
use clap::Parser;

/// Counts heap allocations so `cablevib bench` and `serve` can report allocations per cycle.
#[global_allocator]
static GLOBAL: cablevib::alloc_count::CountingAlloc = cablevib::alloc_count::CountingAlloc;

fn allocations() -> u64 {
    cablevib::alloc_count::allocations()
}

fn main() {
    let cli = cablevib::cli::Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("cablevib: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: cablevib::cli::Cli) -> anyhow::Result<()> {
    cablevib::cli::run(cli, allocations)?;
    Ok(())
}
