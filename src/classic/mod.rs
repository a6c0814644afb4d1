//! The calibration systems of the literature that odocal compares against:
//! the encoder/tachometer chain and heading gain of seed 001, the 6 m square
//! test, UMBmark (Borenstein & Feng 1996), the genetic-algorithm calibration
//! and heading-fusion particle filter of seed 002, and a side-by-side
//! comparison of all of them on the same runs.
//!
//! Pure math on the core robot model: nothing here reads or writes files
//! (`io::seed_tables` reads the seed tables into these types).

mod compare;
mod drive;
mod encoder;
mod error;
mod ga;
mod heading_gain;
mod heading_pf;
mod laser_obs;
mod literature;
mod pf_experiment;
mod sim_runs;
mod square;
mod square_experiment;
mod square_fit;
mod tacho;
mod tacho_experiment;
mod umbmark;
mod umbmark_cycles;

pub use compare::{
    compare_classic, markdown_table, split_short_runs, ClassicMethod, ClassicResult, CompareParams,
    CompareScenario, FinalParams,
};
pub use drive::{
    drive_segments, irregular_path, square_segments, DriveParams, Segment, SimRun, Turn,
};
pub use encoder::EncoderChain;
pub use error::ClassicError;
pub use ga::{
    ga_calibrate, ga_cost, replay_ticks, GaBounds, GaParams, GaResult, GaRun, TickParams,
};
pub use heading_gain::{fit_heading_gain, HeadingGain, HeadingTrial};
pub use heading_pf::{
    heading_pf, simulate_heading, HeadingPfParams, HeadingReading, HeadingSourceParams,
};
pub use laser_obs::{chained_steps, laser_streams, LaserObsParams};
pub use literature::{
    draw_hidden_truth, literature, literature_run, LiteratureParams, LiteratureRow, LiteratureRun,
    LiteratureTable,
};
pub use pf_experiment::{
    calibration_runs, heading_pf_experiment, path_error_markdown, PathErrorRow, PfExperimentParams,
    SeedPathError,
};
pub use sim_runs::{compare_on_simulator, sim_run};
pub use square::{square_report, CornerError, SquareCorner, SquareReport};
pub use square_experiment::{square_experiment, SquareExperiment, SquareExperimentParams};
pub use square_fit::{fit_square_effects, square_odometry_corners, SquareEffectFit};
pub use tacho::{
    fit_tachometer, simulate_tachometer_table, LinearFit, TachoCalibration, TachoReading,
};
pub use tacho_experiment::{tachometer_experiment, SpeedPair, TachometerExperiment};
pub use umbmark::{
    umbmark, umbmark_experiment, umbmark_runs, UmbmarkExperiment, UmbmarkResult, UmbmarkRun,
};
pub use umbmark_cycles::{umbmark_cycles, UmbmarkCycle, UmbmarkCycles, UmbmarkParams};
