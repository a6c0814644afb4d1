//! Making a run visible: a [`Logger`] the pipeline hands its results to (a
//! Rerun recording with the `rerun` feature, [`NullLogger`] otherwise), PNG
//! plots ([`plot`]) and a markdown [`report`]. Nothing here is imported by the
//! math modules; the logger takes plain numbers, poses and points.

mod clock;
pub mod fleet_view;
mod logger;
pub mod plot;
pub mod report;
#[cfg(feature = "rerun")]
mod rerun_fleet;
#[cfg(feature = "rerun")]
mod rerun_layout;
#[cfg(feature = "rerun")]
mod rerun_logger;
pub mod shapes;
mod subsample;
mod trail;

pub use clock::ScanClock;
pub use logger::{entity, CalibEstimate, Logger, NullLogger, Stamp, TrajectoryKind};
#[cfg(feature = "rerun")]
pub use rerun_fleet::{record_fleet, robot_path, DATE};
#[cfg(feature = "rerun")]
pub use rerun_logger::{RerunLogger, RerunOptions, RerunSink};
pub use subsample::systematic_subsample;
pub use trail::{Trail, TrailUpdate};

/// Failures of recording, plotting or report writing.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    /// Writing an output file failed.
    #[error("writing {path}: {source}")]
    Io {
        /// The file being written.
        path: std::path::PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The data handed to the logger or a plot is unusable (lengths differ,
    /// non-finite stamps, nothing to draw).
    #[error("invalid visualisation input: {0}")]
    Input(String),
    /// The Rerun SDK refused a recording, a connection or a viewer spawn.
    #[error("rerun: {0}")]
    Rerun(String),
    /// Drawing or encoding a plot failed.
    #[error("plot: {0}")]
    Plot(String),
}

impl VizError {
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        VizError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
