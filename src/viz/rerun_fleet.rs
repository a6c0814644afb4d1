//! The fleet as a Rerun recording ([`super::fleet_view`]): per robot its
//! parameters over days with ±2σ bands and its alarms, and a blueprint with
//! one plot of both radii per robot and the alarms' log beside them. Written
//! to a temporary file renamed into place when complete.

use super::fleet_view::{FleetRobot, FLEET_PARAMETERS};
use super::rerun_logger::{close, rerun_err, temp_rrd};
use super::VizError;
use rerun::blueprint::{Blueprint, ContainerLike, Grid, Horizontal, TextLogView, TimeSeriesView};
use rerun::components::MarkerShape;
use rerun::{
    Color, EntityPath, EntityPathPart, RecordingStream, RecordingStreamBuilder, Scalars,
    SeriesLines, SeriesPoints, TextLog, TimeColumn,
};
use std::path::Path;

/// The timeline of the recordings' start (UTC).
pub const DATE: &str = "date";

const SECONDS_PER_DAY: f64 = 86_400.0;

/// `fleet/ROBOT[/leaf]`, the robot's name kept whole whatever it holds.
pub fn robot_path(robot: &str, leaf: Option<&str>) -> EntityPath {
    let mut parts = vec![EntityPathPart::new("fleet"), EntityPathPart::new(robot)];
    parts.extend(leaf.map(EntityPathPart::new));
    EntityPath::new(parts)
}

const COLORS: [[u8; 3]; 3] = [[31, 119, 180], [255, 127, 14], [44, 160, 44]];

/// Writes the recording of `robots` to `path` (complete or not at all).
pub fn record_fleet(path: &Path, robots: &[FleetRobot]) -> Result<(), VizError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| VizError::io(dir, e))?;
    }
    let tmp = temp_rrd(path);
    let written = RecordingStreamBuilder::new("odocal-fleet")
        .with_blueprint(blueprint(robots))
        .save(&tmp)
        .map_err(rerun_err)
        .and_then(|rec| {
            for r in robots {
                log_robot(&rec, r)?;
            }
            close(rec, Some((tmp.clone(), path.to_path_buf())))
        });
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

fn dates(days: impl Iterator<Item = f64>) -> TimeColumn {
    TimeColumn::new_timestamp_secs_since_epoch(DATE, days.map(|d| d * SECONDS_PER_DAY))
}

/// One robot: each parameter with its band, the alarm marks and the log.
fn log_robot(rec: &RecordingStream, r: &FleetRobot) -> Result<(), VizError> {
    for (k, (leaf, name)) in FLEET_PARAMETERS.iter().enumerate() {
        let path = robot_path(&r.robot, Some(leaf));
        let [red, green, blue] = COLORS[k];
        let style = SeriesLines::new()
            .with_names([
                name.to_string(),
                format!("{name} −2σ"),
                format!("{name} +2σ"),
            ])
            .with_colors([
                Color::from_rgb(red, green, blue),
                Color::from_unmultiplied_rgba(red, green, blue, 90),
                Color::from_unmultiplied_rgba(red, green, blue, 90),
            ])
            .with_widths([2.0, 1.0, 1.0]);
        rec.log_static(path.clone(), &style).map_err(rerun_err)?;
        if r.calibrations.is_empty() {
            continue;
        }
        let values: Vec<f64> = r
            .calibrations
            .iter()
            .flat_map(|c| {
                let (v, s) = (c.values[k], c.std[k]);
                [v, v - 2.0 * s, v + 2.0 * s]
            })
            .collect();
        let columns = Scalars::new(values)
            .columns(vec![3; r.calibrations.len()])
            .map_err(rerun_err)?;
        let time = dates(r.calibrations.iter().map(|c| c.unix_day));
        rec.send_columns(path, [time], columns).map_err(rerun_err)?;
    }
    log_alarms(rec, r)
}

/// The alarms: a marker on the right radius and a line of the log each.
fn log_alarms(rec: &RecordingStream, r: &FleetRobot) -> Result<(), VizError> {
    if r.alarms.is_empty() {
        return Ok(());
    }
    let marks = robot_path(&r.robot, Some("alarm_marks"));
    let style = SeriesPoints::new()
        .with_names(["alarm"])
        .with_colors([Color::from_rgb(214, 39, 40)])
        .with_markers([MarkerShape::Cross])
        .with_marker_sizes([6.0]);
    rec.log_static(marks.clone(), &style).map_err(rerun_err)?;
    let placed: Vec<(f64, f64)> = r
        .alarms
        .iter()
        .filter_map(|a| Some((a.unix_day, r.mark_height(a.unix_day)?)))
        .collect();
    if !placed.is_empty() {
        let columns = Scalars::new(placed.iter().map(|p| p.1))
            .columns_of_unit_batches()
            .map_err(rerun_err)?;
        rec.send_columns(marks, [dates(placed.iter().map(|p| p.0))], columns)
            .map_err(rerun_err)?;
    }
    let texts: Vec<String> = r
        .alarms
        .iter()
        .map(|a| format!("{} {}: {}", r.robot, a.kind, a.evidence))
        .collect();
    let levels: Vec<&str> = r
        .alarms
        .iter()
        .map(|a| match a.kind.as_str() {
            "fault" => "ERROR",
            "insufficient" => "INFO",
            _ => "WARN",
        })
        .collect();
    let columns = TextLog::update_fields()
        .with_many_text(texts)
        .with_many_level(levels)
        .columns_of_unit_batches()
        .map_err(rerun_err)?;
    let time = dates(r.alarms.iter().map(|a| a.unix_day));
    rec.send_columns(robot_path(&r.robot, Some("alarms")), [time], columns)
        .map_err(rerun_err)
}

/// One plot per robot (both radii with their bands, the alarm marks), in a
/// grid, and the alarms' log of the whole fleet beside it.
fn blueprint(robots: &[FleetRobot]) -> Blueprint {
    let plots: Vec<ContainerLike> = robots
        .iter()
        .map(|r| {
            let leaf = |l: &str| format!("+ /{}", robot_path(&r.robot, Some(l)));
            TimeSeriesView::new(format!("{}: radii (m), ±2σ, alarms ×", r.robot))
                .with_origin(robot_path(&r.robot, None))
                .with_contents([leaf("r_right"), leaf("r_left"), leaf("alarm_marks")])
                .into()
        })
        .collect();
    let log = TextLogView::new("alarms").with_origin("/fleet");
    Blueprint::new(
        Horizontal::new([Grid::new(plots).into(), log.into()]).with_column_shares([3.0, 1.0]),
    )
}
