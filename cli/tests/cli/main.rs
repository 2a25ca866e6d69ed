//! The command line and its files: every command's options and refusals, orientation,
//! CSV files read back by pandas, figures, mode shapes, the sweeps and `sag-compare`.
//! Area binary of the command-line crate (see tests/README.md at the repository root).

mod analyze_realtime;
mod calibrate;
mod cli_hostile;
mod cli_orientation;
mod cli_tool;
mod csv_pandas;
mod figures;
mod frf;
mod hidden_sag;
mod identify;
mod identify_input;
mod identify_input_topic;
mod long_work;
mod map_shard;
mod memory_budget;
mod mode_shapes;
mod outputs;
mod sag_compare;
mod simulate_hostile;
mod stdout_full;
mod sweep;
mod sweep_cli;
