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
    use cablevib::cli::Command;
    match cli.command {
        Command::Analyze(a) => cablevib::cli::analyze(&a)?,
        Command::Bench(a) => cablevib::cli::bench(&a, allocations)?,
        Command::Serve(a) => cablevib::cli::serve(&a, allocations)?,
        Command::Demo(a) => cablevib::cli::demo(&a)?,
        Command::BenchIpc(a) => cablevib::cli::bench_ipc(&a)?,
        Command::Accuracy(a) => cablevib::sweep::accuracy(&a)?,
        Command::Map(a) => cablevib::sweep::map(&a)?,
        Command::Trajectory(a) => cablevib::sweep::trajectory(&a)?,
        Command::SweepTmin(a) => cablevib::sweep::sweep_tmin(&a)?,
    }
    Ok(())
}
