//! The fleet's outputs: `fleet.csv` (one row per recording), `fleet.json`
//! (what `--json` prints), `report.md` (alarms and trends) and `fleet.png`
//! (radii over days per robot with ±2σ bands, alarms marked).

use super::FleetSummary;
use crate::fleet::{Entry, Outcome};
use crate::pipeline::PipelineError;
use crate::viz::plot::{render_line_chart, LineChart, Series};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// One recording in the fleet table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The robot.
    pub robot: String,
    /// The recording.
    pub recording: String,
    /// Its start date (UTC).
    pub date: String,
    /// Days since the epoch.
    pub day: f64,
    /// `calibrated`, `fault` or `insufficient`.
    pub status: String,
    /// Right radius and std (m), when calibrated.
    pub r_right: Option<[f64; 2]>,
    /// Left radius and std (m), when calibrated.
    pub r_left: Option<[f64; 2]>,
    /// Wheel base and std (m), when calibrated.
    pub wheel_base: Option<[f64; 2]>,
    /// Why it was refused.
    pub message: Option<String>,
}

/// The table's rows, in the plan's order.
pub fn rows(entries: &[(String, Entry)], epoch: f64) -> Vec<Row> {
    entries
        .iter()
        .map(|(robot, e)| {
            let mut row = Row {
                robot: robot.clone(),
                recording: e.recording.clone(),
                date: super::inputs::date_of((epoch + e.day).floor() as i64),
                day: e.day,
                status: "calibrated".into(),
                r_right: None,
                r_left: None,
                wheel_base: None,
                message: None,
            };
            match &e.outcome {
                Outcome::Calibrated {
                    params,
                    std,
                    mounting,
                } => {
                    row.r_right = Some([params.r_right, std.r_right]);
                    row.r_left = Some([params.r_left, std.r_left]);
                    row.wheel_base = Some([params.wheel_base, std.wheel_base]);
                    row.message = mounting.clone();
                }
                Outcome::Refused { kind, message } => {
                    row.status = serde_json::to_value(kind)
                        .ok()
                        .and_then(|v| v.as_str().map(String::from))
                        .unwrap_or_default();
                    row.message = Some(message.clone());
                }
            }
            row
        })
        .collect()
}

/// A CSV cell: quoted when it holds a comma, quote or line break.
fn cell(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `fleet.csv`: values in m with 9 decimals (µm resolution and below).
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "robot,recording,date,day,status,r_right_m,r_right_std_m,r_left_m,r_left_std_m,wheel_base_m,wheel_base_std_m,message\n",
    );
    let pair = |v: Option<[f64; 2]>| match v {
        Some([x, e]) => format!("{x:.9},{e:.9}"),
        None => ",".into(),
    };
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{:.6},{},{},{},{},{}",
            cell(&r.robot),
            cell(&r.recording),
            r.date,
            r.day,
            r.status,
            pair(r.r_right),
            pair(r.r_left),
            pair(r.wheel_base),
            cell(r.message.as_deref().unwrap_or(""))
        );
    }
    s
}

/// `report.md`: alarms, then per robot the rates and steps found.
pub fn markdown(s: &FleetSummary) -> String {
    let mut m = format!(
        "# Fleet calibration\n\n{} robots, {} recordings from {} (day 0), method `{}`; {} \
         calibrated in this run, {} from the cache.\n\n## Alarms\n\n",
        s.robot_count, s.recordings, s.epoch, s.method, s.processed, s.cached
    );
    if s.alarms.is_empty() {
        m.push_str("None.\n");
    } else {
        m.push_str("| robot | kind | day | recording | evidence |\n|---|---|---|---|---|\n");
        for a in &s.alarms {
            let _ = writeln!(
                m,
                "| {} | {} | {} | {} | {} |",
                a.robot,
                a.kind.word(),
                a.day,
                a.recording,
                a.evidence.replace('|', "\\|")
            );
        }
    }
    let _ = write!(
        m,
        "\n## Trends\n\nEach recording's std was multiplied by {:.3} (R_R), {:.3} (R_L) and \
         {:.3} (D): the fleet's median scatter between recordings against the std the \
         calibrations report.",
        s.std_factors.r_right, s.std_factors.r_left, s.std_factors.wheel_base
    );
    m.push_str(
        " Rates in mm/day ± std (widened further by the Birge ratio when a robot's scatter \
         exceeds that); steps found in the history.\n\n\
         | robot | recordings | R_R rate | R_L rate | D rate | steps |\n|---|---|---|---|---|---|\n",
    );
    for r in &s.robots {
        let rate = |p: &str| {
            r.trends
                .iter()
                .find(|t| t.parameter == p)
                .map(|t| {
                    format!(
                        "{:+.4} ± {:.4}",
                        1e3 * t.rate_m_per_day,
                        1e3 * t.rate_std_m_per_day
                    )
                })
                .unwrap_or_else(|| "too few calibrations".into())
        };
        let steps: Vec<String> = r
            .trends
            .iter()
            .flat_map(|t| {
                t.steps.iter().map(move |st| {
                    format!(
                        "{} {:+.2} mm on day {}",
                        t.parameter,
                        1e3 * st.size_m,
                        st.day
                    )
                })
            })
            .collect();
        let _ = writeln!(
            m,
            "| {} | {} | {} | {} | {} | {} |",
            r.robot,
            r.recordings,
            rate("r_right"),
            rate("r_left"),
            rate("wheel_base"),
            if steps.is_empty() {
                "none".into()
            } else {
                steps.join("; ")
            }
        );
    }
    m.push_str("\n![radii over days](fleet.png)\n");
    m
}

/// Robots drawn in `fleet.png`: those with alarms first, then the others,
/// at most this many.
const MAX_PANELS: usize = 12;

/// `fleet.png`: per robot, both radii (mm) over days with ±2σ bands
/// (dashed) and a vertical line at each alarm's day.
fn figure(s: &FleetSummary) -> Option<LineChart> {
    let mut order: Vec<&str> = s.alarms.iter().map(|a| a.robot.as_str()).collect();
    order.dedup();
    for r in &s.robots {
        if !order.contains(&r.robot.as_str()) {
            order.push(&r.robot);
        }
    }
    order.truncate(MAX_PANELS);
    let title = format!(
        "Radii over days ({} of {} robots, alarms first; bands ±2σ as each calibration reports it)",
        order.len(),
        s.robot_count
    );
    let mut chart = LineChart::new(title, format!("day (0 = {})", s.epoch));
    for robot in order {
        let rows: Vec<&super::Row> = s.table.iter().filter(|r| r.robot == robot).collect();
        let mut series = Vec::new();
        for (name, pick, color) in [
            (
                "R_R",
                (|r: &super::Row| r.r_right) as fn(&super::Row) -> Option<[f64; 2]>,
                [31, 119, 180],
            ),
            ("R_L", |r: &super::Row| r.r_left, [255, 127, 14]),
        ] {
            let pts: Vec<[f64; 3]> = rows
                .iter()
                .filter_map(|r| pick(r).map(|[v, e]| [r.day, 1e3 * v, 2e3 * e]))
                .collect();
            series.push(Series::new(name, pts.iter().map(|p| [p[0], p[1]]).collect()).color(color));
            for sign in [-1.0, 1.0] {
                let band = pts.iter().map(|p| [p[0], p[1] + sign * p[2]]).collect();
                series.push(
                    Series::new(format!("{name} ±2σ"), band)
                        .color(color)
                        .dashed(),
                );
            }
        }
        let values: Vec<f64> = series
            .iter()
            .flat_map(|x| x.points.iter().map(|p| p[1]))
            .collect();
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        for a in s.alarms.iter().filter(|a| a.robot == robot) {
            let line = if lo.is_finite() {
                vec![[a.day, lo], [a.day, hi]]
            } else {
                Vec::new()
            };
            let color = match a.kind {
                crate::fleet::AlarmKind::Wear => [148, 103, 189],
                crate::fleet::AlarmKind::Step => [214, 39, 40],
                crate::fleet::AlarmKind::Fault => [0, 0, 0],
                crate::fleet::AlarmKind::Insufficient => [127, 127, 127],
            };
            series.push(Series::new(format!("alarm: {}", a.kind.word()), line).color(color));
        }
        chart = chart.panel(format!("{robot}: radius (mm)"), series);
    }
    chart.size.1 = chart.size.1.min(60 + 260 * chart.panels.len() as u32);
    Some(chart).filter(|c| !c.panels.is_empty())
}

/// Writes the table, the JSON, the report and the figure into `out`
/// (each atomically); returns their paths.
pub fn write(out: &Path, s: &FleetSummary) -> Result<Vec<String>, PipelineError> {
    std::fs::create_dir_all(out).map_err(|e| PipelineError::write(out, e))?;
    let put = |name: &str, bytes: &[u8]| -> Result<String, PipelineError> {
        let p = out.join(name);
        crate::io::atomic::write_bytes_atomic(&p, bytes)
            .map_err(|e| PipelineError::write(&p, e))?;
        Ok(p.display().to_string())
    };
    let mut written = vec![put("fleet.csv", csv(&s.table).as_bytes())?];
    if let Some(chart) = figure(s) {
        let png = render_line_chart(&chart)
            .and_then(|img| img.to_png())
            .map_err(|e| PipelineError::write(&out.join("fleet.png"), e))?;
        written.push(put("fleet.png", &png)?);
    }
    written.push(put("report.md", markdown(s).as_bytes())?);
    let json_path = out.join("fleet.json").display().to_string();
    written.push(json_path);
    let mut with_outputs = s.clone();
    with_outputs.outputs = written.clone();
    let json =
        serde_json::to_string_pretty(&with_outputs).map_err(|e| PipelineError::write(out, e))?;
    put("fleet.json", json.as_bytes())?;
    Ok(written)
}
