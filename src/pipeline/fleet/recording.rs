//! `odocal fleet --rrd FILE`: the fleet's Rerun recording
//! ([`crate::viz::fleet_view`]), made from the table and the alarms, so that
//! it is the same whichever engine calibrated the recordings (the Ray engine
//! leaves them in `fleet.json`, read back here).

use super::report::Row;
use super::FleetSummary;
use crate::fleet::Alarm;
use crate::io::out_lock::OutputLock;
use crate::pipeline::outputs::{check_outputs, lock_outputs};
use crate::pipeline::PipelineError;
use crate::viz::fleet_view::{FleetMark, FleetPoint, FleetRobot};
use serde::Deserialize;
use std::path::Path;

/// The files of the fleet's output folder that `--rrd` must not name.
const OUT_FILES: [&str; 4] = ["fleet.csv", "fleet.json", "report.md", "fleet.png"];

/// Checks `rrd` against the fleet's other outputs and the source, and
/// locks it for the run: call before any work.
pub fn claim(rrd: &Path, source: &Path, out: &Path) -> Result<Vec<OutputLock>, PipelineError> {
    record(rrd, None)?;
    let files: Vec<_> = OUT_FILES.iter().map(|f| out.join(f)).collect();
    // The output folder may not exist yet: compare the paths as written too.
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    if let Some(f) = files.iter().find(|f| abs(f) == abs(rrd)) {
        return Err(PipelineError::BadArgument(format!(
            "--rrd {} is the fleet's output {}: choose another path for the recording",
            rrd.display(),
            f.display()
        )));
    }
    let mut outputs: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    outputs.push(rrd);
    let inputs: Vec<&Path> = if source.is_file() {
        vec![source]
    } else {
        Vec::new()
    };
    check_outputs(&inputs, &outputs)?;
    lock_outputs(&[rrd])
}

/// Per robot, its calibrations and alarms placed in time (`epoch`: the
/// unix day of the table's day 0).
pub fn robots(table: &[Row], alarms: &[Alarm], epoch: f64) -> Vec<FleetRobot> {
    let mut robots: Vec<FleetRobot> = Vec::new();
    for row in table {
        let at = match robots.iter().position(|r| r.robot == row.robot) {
            Some(at) => at,
            None => {
                robots.push(FleetRobot {
                    robot: row.robot.clone(),
                    ..Default::default()
                });
                robots.len() - 1
            }
        };
        let robot = &mut robots[at];
        if let (Some(rr), Some(rl), Some(d)) = (row.r_right, row.r_left, row.wheel_base) {
            robot.calibrations.push(FleetPoint {
                unix_day: epoch + row.day,
                values: [rr[0], rl[0], d[0]],
                std: [rr[1], rl[1], d[1]],
            });
        }
    }
    for a in alarms {
        if let Some(r) = robots.iter_mut().find(|r| r.robot == a.robot) {
            r.alarms.push(FleetMark {
                unix_day: epoch + a.day,
                kind: a.kind.word().to_string(),
                evidence: a.evidence.clone(),
            });
        }
    }
    for r in &mut robots {
        r.calibrations
            .sort_by(|a, b| a.unix_day.total_cmp(&b.unix_day));
        r.alarms.sort_by(|a, b| a.unix_day.total_cmp(&b.unix_day));
    }
    robots
}

/// What the recording needs of `fleet.json`.
#[derive(Deserialize)]
struct Written {
    epoch: String,
    alarms: Vec<Alarm>,
    table: Vec<Row>,
}

fn epoch_day(epoch: &str, whence: &Path) -> Result<f64, PipelineError> {
    super::inputs::find_date(epoch).ok_or_else(|| {
        PipelineError::BadArgument(format!(
            "{}: epoch {epoch:?} is not a date YYYY-MM-DD",
            whence.display()
        ))
    })
}

/// Writes the recording of a fleet run (atomically).
pub fn write(rrd: &Path, s: &FleetSummary) -> Result<(), PipelineError> {
    let epoch = epoch_day(&s.epoch, rrd)?;
    record(rrd, Some(&robots(&s.table, &s.alarms, epoch)))
}

/// Writes the recording of the fleet run whose outputs are in `out` (its
/// `fleet.json`), as the Ray engine leaves them.
pub fn write_from(rrd: &Path, out: &Path) -> Result<(), PipelineError> {
    let json = out.join("fleet.json");
    let text = std::fs::read_to_string(&json).map_err(|e| {
        PipelineError::BadArgument(format!(
            "{}: cannot read the fleet's results ({e})",
            json.display()
        ))
    })?;
    let w: Written = serde_json::from_str(&text).map_err(|e| {
        PipelineError::BadArgument(format!("{}: not a fleet result ({e})", json.display()))
    })?;
    let epoch = epoch_day(&w.epoch, &json)?;
    record(rrd, Some(&robots(&w.table, &w.alarms, epoch)))
}

/// Writes `robots` to `rrd`; with `None`, only checks that this build can.
#[cfg(feature = "rerun")]
fn record(rrd: &Path, robots: Option<&[FleetRobot]>) -> Result<(), PipelineError> {
    let Some(robots) = robots else {
        return Ok(());
    };
    crate::viz::record_fleet(rrd, robots).map_err(|e| PipelineError::Write {
        path: rrd.display().to_string(),
        message: e.to_string(),
    })
}

/// Refused: this build has no Rerun.
#[cfg(not(feature = "rerun"))]
fn record(_: &Path, _: Option<&[FleetRobot]>) -> Result<(), PipelineError> {
    Err(PipelineError::BadArgument(
        "this odocal was built without the `rerun` feature: no Rerun recording".into(),
    ))
}
