//! The implemented papers' tables and figures regenerated on our own data,
//! above the math modules: Monte Carlo over synthetic and simulated wheelchair
//! runs (\[Farina\]), every method of the literature side by side, the square
//! and tachometer tables of \[Paryanto\], the GA and heading-fusion table of
//! \[GAHeading\], and UMBmark on simulated robots. [`run`] is
//! `odocal experiment NAME`: it writes each experiment as `NAME.md`,
//! `NAME.json` and `NAME.png`. Experiments sit
//! above the pipeline too: they run ICP on simulated scans through it.
//!
//! The algorithms live in `calib` and `classic`; this module drives them over
//! simulated runs, summarises, and turns the papers' published tables
//! (`io::seed_tables`) into their inputs.

pub mod blind;
mod compare;
mod driver;
pub mod fleet;
mod heading_pf;
mod inputs;
mod literature;
mod montecarlo;
mod output;
mod repetitions;
mod square;
mod stats;
mod tachometer;
mod umbmark;

pub use compare::{
    compare_classic, compare_on_simulator, markdown_table, sim_run, split_short_runs,
    ClassicMethod, ClassicResult, CompareParams, CompareScenario,
};
pub use driver::{run, run_experiment, ExperimentJob, ExperimentSettings, EXPERIMENTS};
pub use heading_pf::{
    calibration_runs, ga_path_errors, heading_pf_experiment, path_error_markdown, PathErrorRow,
    PfExperimentParams, SeedPathError,
};
pub use inputs::ExperimentInputs;
pub use literature::{
    literature, literature_run, LiteratureParams, LiteratureRow, LiteratureRun, LiteratureTable,
};
pub use montecarlo::{
    changing_configs, changing_figure, fixed_count_label, montecarlo, montecarlo_with,
    scan_montecarlo, score, table1_configs, table2_configs, Fig5, MonteCarloParams, MonteCarloRuns,
    MonteCarloTable, PreparedRun, RunFigures, RunMetrics, RunTruth, ScanMonteCarloParams, TableRow,
    FIG5_FIXED_PARTICLES,
};
pub use output::ExperimentOutput;
pub use repetitions::draw_hidden_truth;
pub use square::{square_corners, square_experiment, SquareExperiment, SquareExperimentParams};
pub use stats::Stat;
pub use tachometer::{
    heading_trials, speed_pairs, tachometer_experiment, tachometer_table, SpeedPair,
    TachometerExperiment,
};
pub use umbmark::{
    umbmark_cycles, umbmark_experiment, UmbmarkCycle, UmbmarkCycles, UmbmarkExperiment,
    UmbmarkParams,
};
