//! The topics of an MCAP whose messages could be a trajectory (`Odometry`,
//! `PoseStamped`, `PointStamped`), read from its summary section, so that a
//! command finding nothing on the configured topics can name the ones to set.

use crate::error::InputError;
use std::path::Path;

/// Message types a reference or odometry trajectory can come as.
const TRAJECTORY_TYPES: [&str; 3] = [
    "nav_msgs/msg/Odometry",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PointStamped",
];

/// `(topic, type)` of every channel holding a trajectory message type, sorted
/// by topic; empty when the file has no summary section.
pub fn trajectory_topics(path: &Path) -> Result<Vec<(String, String)>, InputError> {
    let file = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| InputError::new(&file, format!("cannot read: {e}")))?;
    let Ok(Some(summary)) = mcap::Summary::read(&bytes) else {
        return Ok(Vec::new());
    };
    let mut out: Vec<(String, String)> = summary
        .channels
        .values()
        .filter_map(|ch| {
            let ty = ch.schema.as_ref()?.name.replace("/msg/", "/");
            TRAJECTORY_TYPES
                .iter()
                .find(|t| t.replace("/msg/", "/") == ty)
                .map(|t| (ch.topic.clone(), t.to_string()))
        })
        .collect();
    out.sort();
    out.dedup();
    Ok(out)
}
