//! Errors of a pipeline run, with the exit code the binary returns for each.

use crate::error::InputError;

/// Why a command failed. [`exit_code`](PipelineError::exit_code) is 2 for bad
/// input or arguments and 1 for anything else.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// A file that cannot be used (names file, topic, position).
    #[error(transparent)]
    Input(#[from] InputError),
    /// An argument or configuration value that cannot be used.
    #[error("{0}")]
    BadArgument(String),
    /// The inputs are readable but cannot be evaluated (no overlap, too few poses).
    #[error(transparent)]
    Eval(#[from] crate::eval::EvalError),
    /// A simulation that cannot be set up with these settings.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
    /// The network side of a live run could not be set up (DDS).
    #[error("network: {0}")]
    Network(String),
    /// Writing an output failed (disk full, permissions).
    #[error("cannot write {path}: {message}")]
    Write {
        /// The output path.
        path: String,
        /// What went wrong.
        message: String,
    },
}

impl PipelineError {
    /// Process exit code: 2 for bad input or arguments, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            Self::Input(_) | Self::BadArgument(_) | Self::Eval(_) | Self::Sim(_) => 2,
            Self::Write { .. } | Self::Network(_) => 1,
        }
    }

    /// A write error for `path`.
    pub fn write(path: &std::path::Path, e: impl std::fmt::Display) -> Self {
        Self::Write {
            path: path.display().to_string(),
            message: e.to_string(),
        }
    }
}
