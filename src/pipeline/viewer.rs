//! Where a run is shown in the Rerun viewer: a recording file, a running
//! viewer, or one spawned for it. Without the `rerun` feature, asking for any
//! of them is refused with a message saying so.

use super::PipelineError;
use crate::viz::{Logger, VizError};
use std::path::PathBuf;

/// A Rerun destination.
#[derive(Debug, Clone, PartialEq)]
pub enum Viewer {
    /// Write a recording (`.rrd`).
    File(PathBuf),
    /// Stream to a running viewer at this address.
    Connect(String),
    /// Spawn the viewer (when installed) and stream to it.
    Spawn,
}

/// The error of a failed recording.
pub(crate) fn viz_error(e: VizError) -> PipelineError {
    PipelineError::Write {
        path: "rerun recording".into(),
        message: e.to_string(),
    }
}

/// The logger for `viewer`; `None` when none is asked for.
#[cfg(feature = "rerun")]
pub fn open_logger(viewer: Option<&Viewer>) -> Result<Option<Box<dyn Logger>>, PipelineError> {
    use crate::viz::{RerunLogger, RerunOptions, RerunSink};
    let sink = match viewer {
        None => return Ok(None),
        Some(Viewer::File(f)) => RerunSink::File(f.clone()),
        Some(Viewer::Connect(addr)) => RerunSink::Connect(addr.clone()),
        Some(Viewer::Spawn) => RerunSink::Spawn,
    };
    let logger = RerunLogger::new(sink, RerunOptions::default()).map_err(viz_error)?;
    Ok(Some(Box::new(logger)))
}

/// The logger for `viewer`; `None` when none is asked for.
#[cfg(not(feature = "rerun"))]
pub fn open_logger(viewer: Option<&Viewer>) -> Result<Option<Box<dyn Logger>>, PipelineError> {
    match viewer {
        None => Ok(None),
        Some(_) => Err(PipelineError::BadArgument(
            "this odocal was built without the `rerun` feature: no Rerun recording".into(),
        )),
    }
}
