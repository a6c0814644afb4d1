//! The calibration systems of the literature that odocal compares against:
//! the encoder/tachometer chain and heading gain of \[Paryanto\], the 6 m square
//! test, UMBmark \[Borenstein1996\], the genetic-algorithm calibration
//! and heading-fusion particle filter of \[GAHeading\], and the robot that drives
//! their runs by its own odometry.
//!
//! Pure math on the core robot model: nothing here reads or writes files.

mod drive;
mod encoder;
mod error;
mod ga;
mod heading_gain;
mod heading_pf;
mod laser_obs;
mod square;
mod square_fit;
mod tacho;
mod tacho_session;
mod umbmark;

pub use drive::{
    drive_segments, irregular_path, square_segments, DriveParams, Segment, SimRun, Turn,
};
pub use encoder::EncoderChain;
pub(crate) use error::check_finite;
pub use error::ClassicError;
pub use ga::{
    ga_calibrate, ga_cost, replay_ticks, GaBounds, GaParams, GaResult, GaRun, TickParams,
};
pub use heading_gain::{fit_heading_gain, HeadingGain, HeadingTrial};
pub use heading_pf::{
    heading_pf, simulate_heading, HeadingPfParams, HeadingReading, HeadingSourceParams,
};
pub use laser_obs::{chained_steps, chained_steps_from, laser_streams, LaserObsParams};
pub use square::{square_report, CornerError, SquareCorner, SquareReport};
pub use square_fit::{
    fit_square_effects, measured_square, square_odometry_corners, SquareEffectFit,
};
pub use tacho::{fit_tachometer, LinearFit, TachoCalibration, TachoReading};
pub use tacho_session::{session_speeds, tachometer_session, TachometerSensor};
pub use umbmark::{umbmark, umbmark_runs, UmbmarkResult, UmbmarkRun};
