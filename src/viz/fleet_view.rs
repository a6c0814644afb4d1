//! What the fleet's Rerun recording shows, as plain data: per robot the
//! calibrations over days with their std, and the alarms. Entity paths:
//! `fleet/ROBOT/{r_right,r_left,wheel_base}` (each a scalar series with its
//! ±2σ band as two more series), `fleet/ROBOT/alarm_marks` (a marker per
//! alarm on the right radius) and `fleet/ROBOT/alarms` (the alarms' words and
//! evidence as a text log), on the timeline `date` (the recording's start,
//! UTC).

/// One calibrated recording.
#[derive(Debug, Clone, PartialEq)]
pub struct FleetPoint {
    /// When the recording started (days since 1970-01-01, UTC).
    pub unix_day: f64,
    /// `[R_R, R_L, D]` (m).
    pub values: [f64; 3],
    /// Their std as the calibration reports it (m).
    pub std: [f64; 3],
}

/// One alarm.
#[derive(Debug, Clone, PartialEq)]
pub struct FleetMark {
    /// The alarm's day (days since 1970-01-01, UTC).
    pub unix_day: f64,
    /// `wear`, `step`, `fault` or `insufficient`.
    pub kind: String,
    /// The evidence in words.
    pub evidence: String,
}

/// One robot's history.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FleetRobot {
    /// The robot's name.
    pub robot: String,
    /// Its calibrated recordings, by time.
    pub calibrations: Vec<FleetPoint>,
    /// Its alarms, by time.
    pub alarms: Vec<FleetMark>,
}

/// The parameters' entity names under `fleet/ROBOT`, with their display names.
pub const FLEET_PARAMETERS: [(&str, &str); 3] =
    [("r_right", "R_R"), ("r_left", "R_L"), ("wheel_base", "D")];

impl FleetRobot {
    /// Where an alarm is marked on the right-radius plot: the right radius of
    /// the calibration at the alarm's day, or of the nearest one in time when
    /// that day's recording was refused; `None` without any calibration.
    pub fn mark_height(&self, unix_day: f64) -> Option<f64> {
        self.calibrations
            .iter()
            .min_by(|a, b| {
                let da = (a.unix_day - unix_day).abs();
                let db = (b.unix_day - unix_day).abs();
                da.total_cmp(&db)
            })
            .map(|c| c.values[0])
    }
}
