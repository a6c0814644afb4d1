//! `odocal experiment fleet`: a simulated fleet with hidden histories, run
//! through `odocal fleet`, and the alarms compared with the truth. Each
//! robot (`--runs` of them) records one run a day for `days` days; its
//! history, kept apart in `fleet-truth.json`, is one of: tyre wear (both
//! radii shrink at a drawn rate), a step (one radius changes on a drawn
//! day: a new user, a repair), a wiring swap (from a drawn day the encoder
//! joints are swapped in the bag, as after a repair), a short recording (one
//! day drives only 8 s straight: too little motion), a knocked laser (from a
//! drawn day the laser is turned by a drawn yaw while the bag still states
//! its old mounting), or nothing.

use super::inputs::{bad, ExperimentInputs};
use super::output::ExperimentOutput;
use crate::effects::Effect;
use crate::fleet::AlarmKind;
use crate::pipeline::fleet::{self, inputs::date_of, FleetJob, FleetSummary};
use crate::pipeline::{Common, Config, PipelineError};
use crate::robot::RobotConfig;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Settings of `odocal experiment fleet` (table `[fleet]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FleetSimParams {
    /// Days each robot records (one recording a day).
    pub days: usize,
    /// Length of each recording (s).
    pub duration_s: f64,
    /// The simulator's scenario for every recording.
    pub scenario: String,
    /// Tyre wear rate range (mm/day, radius lost per day).
    pub wear_mm_per_day: [f64; 2],
    /// Step size range (mm, either sign, on one wheel).
    pub step_mm: [f64; 2],
    /// Each robot's radii differ from nominal by up to this (relative).
    pub spread: f64,
    /// Length of the short recording (s).
    pub short_duration_s: f64,
    /// Yaw range of a knocked laser (rad, either sign).
    pub knock_rad: [f64; 2],
    /// The date of day 0.
    pub start_date: String,
}

impl Default for FleetSimParams {
    fn default() -> Self {
        Self {
            days: 8,
            duration_s: 60.0,
            scenario: "corridor-loop".into(),
            wear_mm_per_day: [0.3, 0.6],
            step_mm: [2.0, 4.0],
            spread: 0.005,
            short_duration_s: 8.0,
            knock_rad: [0.04, 0.08],
            start_date: "2026-01-05".into(),
        }
    }
}

/// A robot's hidden history.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "history", rename_all = "lowercase")]
pub enum History {
    /// Both radii shrink by `mm_per_day` each day.
    Wear {
        /// Rate (mm/day).
        mm_per_day: f64,
    },
    /// One radius changes by `mm` from `day` on.
    Step {
        /// First day after the step.
        day: usize,
        /// `right` or `left`.
        wheel: String,
        /// Size (mm).
        mm: f64,
    },
    /// The encoder joints are swapped in the bags from `day` on.
    Swap {
        /// First day with the swap.
        day: usize,
    },
    /// The recording of `day` is only a short straight drive.
    Short {
        /// Its day.
        day: usize,
    },
    /// The laser is turned by `yaw` from `day` on; the bags still state
    /// its old mounting.
    Knocked {
        /// First day turned.
        day: usize,
        /// Its turn (rad).
        yaw: f64,
    },
    /// Nothing happens.
    Nothing,
}

/// One simulated robot: its history and its radii's relative offsets.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobotTruth {
    /// Its name.
    pub robot: String,
    /// What happens to it.
    #[serde(flatten)]
    pub history: History,
    /// Right and left radius offsets from nominal on day 0 (relative).
    pub radius_scale: [f64; 2],
}

/// The histories of `n` robots: wear, step, swap, short, knocked, nothing,
/// nothing, repeated, each with its numbers drawn from `seed`.
pub fn draw_histories(n: usize, seed: u64, p: &FleetSimParams) -> Vec<RobotTruth> {
    let mut rng = StdRng::seed_from_u64(seed);
    let last = p.days.saturating_sub(1).max(2);
    (0..n)
        .map(|i| {
            let history = match i % 7 {
                0 => History::Wear {
                    mm_per_day: rng.random_range(p.wear_mm_per_day[0]..=p.wear_mm_per_day[1]),
                },
                1 => History::Step {
                    day: rng.random_range(2..=last.saturating_sub(1).max(2)),
                    wheel: if rng.random_bool(0.5) {
                        "right"
                    } else {
                        "left"
                    }
                    .into(),
                    mm: rng.random_range(p.step_mm[0]..=p.step_mm[1])
                        * if rng.random_bool(0.5) { 1.0 } else { -1.0 },
                },
                2 => History::Swap {
                    day: rng.random_range(2..=last),
                },
                3 => History::Short {
                    day: rng.random_range(1..=last),
                },
                4 => History::Knocked {
                    day: rng.random_range(2..=last.saturating_sub(1).max(2)),
                    yaw: rng.random_range(p.knock_rad[0]..=p.knock_rad[1])
                        * if rng.random_bool(0.5) { 1.0 } else { -1.0 },
                },
                _ => History::Nothing,
            };
            RobotTruth {
                robot: format!("chair-{:02}", i + 1),
                history,
                radius_scale: [
                    rng.random_range(-p.spread..=p.spread),
                    rng.random_range(-p.spread..=p.spread),
                ],
            }
        })
        .collect()
}

/// The true laser yaw offset (rad) of `t` on `day`.
fn knock_on(t: &RobotTruth, day: usize) -> f64 {
    match &t.history {
        History::Knocked { day: s, yaw } if day >= *s => *yaw,
        _ => 0.0,
    }
}

/// The true radii changes (m) of `t` on `day`, and whether its joints are
/// swapped and its run is short.
fn state_on(t: &RobotTruth, day: usize) -> ([f64; 2], bool, bool) {
    match &t.history {
        History::Wear { mm_per_day } => {
            let d = -1e-3 * mm_per_day * day as f64;
            ([d, d], false, false)
        }
        History::Step { day: s, wheel, mm } if day >= *s => {
            let d = 1e-3 * mm;
            (
                if wheel == "right" { [d, 0.0] } else { [0.0, d] },
                false,
                false,
            )
        }
        History::Swap { day: s } => ([0.0; 2], day >= *s, false),
        History::Short { day: s } => ([0.0; 2], false, day == *s),
        _ => ([0.0; 2], false, false),
    }
}

/// Simulates robot `t`'s recording of `day` into `path`.
fn simulate_day(
    t: &RobotTruth,
    index: usize,
    day: usize,
    seed: u64,
    robot: &RobotConfig,
    p: &FleetSimParams,
    path: &Path,
) -> Result<(), PipelineError> {
    let mut cfg = Config::default();
    let (delta, swapped, short) = state_on(t, day);
    cfg.sim.scenario.name = p.scenario.clone();
    cfg.sim.duration_s = if short {
        p.short_duration_s
    } else {
        p.duration_s
    };
    cfg.sim.seed = seed
        .wrapping_mul(1_000_003)
        .wrapping_add(index as u64 * 1009 + day as u64);
    let mut sim_robot = robot.clone();
    sim_robot.laser = Some(robot.laser.unwrap_or_default());
    if swapped {
        std::mem::swap(&mut sim_robot.left_joint, &mut sim_robot.right_joint);
    }
    let scale = |k: usize, r: f64| t.radius_scale[k] + delta[k] / r;
    let spec = format!(
        "radius_scale:right={:.9},left={:.9}",
        scale(0, robot.r_right),
        scale(1, robot.r_left)
    );
    let mut effects = vec![Effect::parse(&spec).map_err(|e| bad(e.to_string()))?];
    let yaw = knock_on(t, day);
    if yaw != 0.0 {
        let knock = format!("laser_offset:yaw={yaw:.9}");
        effects.push(Effect::parse(&knock).map_err(|e| bad(e.to_string()))?);
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| PipelineError::write(dir, e))?;
    }
    crate::pipeline::simulate::simulate(
        &cfg.sim,
        &cfg.topics,
        &sim_robot,
        &effects,
        path,
        None,
        &mut |_| {},
    )?;
    Ok(())
}

/// Writes the fleet's bags under `data/ROBOT/DATE/run.mcap` (in parallel)
/// and `data/manifest.csv`.
pub fn generate(
    truths: &[RobotTruth],
    seed: u64,
    robot: &RobotConfig,
    p: &FleetSimParams,
    data: &Path,
) -> Result<PathBuf, PipelineError> {
    use rayon::prelude::*;
    let day0 = crate::pipeline::fleet::inputs::find_date(&p.start_date).ok_or_else(|| {
        bad(format!(
            "fleet.start_date '{}' is not a date YYYY-MM-DD",
            p.start_date
        ))
    })? as i64;
    let jobs: Vec<(usize, usize)> = (0..truths.len())
        .flat_map(|i| (0..p.days).map(move |d| (i, d)))
        .collect();
    let rel =
        |i: usize, d: usize| format!("{}/{}/run.mcap", truths[i].robot, date_of(day0 + d as i64));
    jobs.par_iter()
        .map(|&(i, d)| simulate_day(&truths[i], i, d, seed, robot, p, &data.join(rel(i, d))))
        .collect::<Result<Vec<()>, PipelineError>>()?;
    let mut manifest = String::from("robot,path,start\n");
    for &(i, d) in &jobs {
        manifest.push_str(&format!(
            "{},{},{}\n",
            truths[i].robot,
            rel(i, d),
            date_of(day0 + d as i64)
        ));
    }
    let path = data.join("manifest.csv");
    crate::io::atomic::write_bytes_atomic(&path, manifest.as_bytes())
        .map_err(|e| PipelineError::write(&path, e))?;
    Ok(path)
}

/// How one robot's alarms compare with its history.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobotVerdict {
    /// The robot.
    pub robot: String,
    /// Its history in words.
    pub truth: String,
    /// Its alarms in words.
    pub found: String,
    /// Estimated wear rate (mm/day, mean of both radii) over the true one,
    /// for a worn robot.
    pub rate_ratio: Option<f64>,
    /// Whether the alarms are exactly the events (rates within 20 %).
    pub correct: bool,
}

/// The alarms the history should raise: (kind, day; `None` for wear).
fn expected(t: &RobotTruth) -> Vec<(AlarmKind, Option<usize>)> {
    match &t.history {
        History::Wear { .. } => vec![(AlarmKind::Wear, None)],
        History::Step { day, .. } => vec![(AlarmKind::Step, Some(*day))],
        History::Swap { day } => vec![(AlarmKind::Fault, Some(*day))],
        History::Short { day } => vec![(AlarmKind::Insufficient, Some(*day))],
        History::Knocked { day, .. } => vec![(AlarmKind::Fault, Some(*day))],
        History::Nothing => Vec::new(),
    }
}

/// Compares each robot's alarms with its history.
pub fn judge(truths: &[RobotTruth], run: &FleetSummary) -> Vec<RobotVerdict> {
    truths
        .iter()
        .map(|t| {
            let alarms: Vec<_> = run.alarms.iter().filter(|a| a.robot == t.robot).collect();
            let found: Vec<(AlarmKind, Option<usize>)> = alarms
                .iter()
                .map(|a| {
                    let day = (a.kind != AlarmKind::Wear).then_some(a.day.round() as usize);
                    (a.kind, day)
                })
                .collect();
            let rate_ratio = match (&t.history, alarms.first()) {
                (History::Wear { mm_per_day }, Some(a)) if a.kind == AlarmKind::Wear => {
                    let r = a
                        .values
                        .get("r_right_m_per_day")
                        .copied()
                        .unwrap_or(f64::NAN);
                    let l = a
                        .values
                        .get("r_left_m_per_day")
                        .copied()
                        .unwrap_or(f64::NAN);
                    Some(-0.5e3 * (r + l) / mm_per_day)
                }
                _ => None,
            };
            let rate_ok = rate_ratio.is_none_or(|q| (q - 1.0).abs() <= 0.2);
            RobotVerdict {
                robot: t.robot.clone(),
                truth: describe(&t.history),
                found: if alarms.is_empty() {
                    "none".into()
                } else {
                    alarms
                        .iter()
                        .map(|a| format!("{} (day {})", a.kind.word(), a.day))
                        .collect::<Vec<_>>()
                        .join(", ")
                },
                rate_ratio,
                correct: found == expected(t) && rate_ok,
            }
        })
        .collect()
}

fn describe(h: &History) -> String {
    match h {
        History::Wear { mm_per_day } => format!("wear {mm_per_day:.3} mm/day"),
        History::Step { day, wheel, mm } => format!("step {mm:+.2} mm {wheel} on day {day}"),
        History::Swap { day } => format!("wiring swap from day {day}"),
        History::Short { day } => format!("short recording on day {day}"),
        History::Knocked { day, yaw } => format!("laser knocked {yaw:+.3} rad on day {day}"),
        History::Nothing => "nothing".into(),
    }
}

/// What `odocal experiment fleet` writes to `fleet.json`.
#[derive(Debug, Clone, Serialize)]
struct FleetExperiment<'a> {
    robots: usize,
    days: usize,
    duration_s: f64,
    correct: usize,
    wall_s_generate: f64,
    wall_s_fleet: f64,
    threads: usize,
    verdicts: &'a [RobotVerdict],
    truth: &'a [RobotTruth],
}

/// Runs `odocal experiment fleet`: generate (`OUT/fleet-data/`, truth in
/// `OUT/fleet-truth.json`), run the fleet (`OUT/fleet-run/`), judge.
pub fn fleet_output(
    inp: &ExperimentInputs<'_>,
    p: &FleetSimParams,
    out: &Path,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    if p.days < 5 || !(p.duration_s > 0.0) {
        return Err(bad(
            "fleet: days must be at least 5 and duration_s positive",
        ));
    }
    let truths = draw_histories(inp.runs, inp.seed, p);
    let t0 = std::time::Instant::now();
    let manifest = generate(&truths, inp.seed, inp.robot, p, &out.join("fleet-data"))?;
    let truth_path = out.join("fleet-truth.json");
    let truth_json = serde_json::to_string_pretty(&truths).map_err(|e| bad(e.to_string()))?;
    crate::io::atomic::write_bytes_atomic(&truth_path, truth_json.as_bytes())
        .map_err(|e| PipelineError::write(&truth_path, e))?;
    let wall_generate = t0.elapsed().as_secs_f64();
    let job = FleetJob {
        source: manifest,
        out: out.join("fleet-run"),
        choice: Default::default(),
        common: Common::default(),
    };
    let t1 = std::time::Instant::now();
    let run = fleet::run(&job, &|_, _| {})?;
    let wall_fleet = t1.elapsed().as_secs_f64();
    let _ = std::fs::copy(out.join("fleet-run/fleet.png"), png);
    let verdicts = judge(&truths, &run);
    let correct = verdicts.iter().filter(|v| v.correct).count();
    let mut md = format!(
        "{} robots × {} days × {} s ({} scenario); {} of {} robots' alarms are exactly their \
         events (wear rates within 20 %). Simulating took {:.0} s, the fleet run {:.0} s on {} \
         threads.\n\n| robot | truth | alarms | rate est./true | right |\n|---|---|---|---|---|\n",
        inp.runs,
        p.days,
        p.duration_s,
        p.scenario,
        correct,
        verdicts.len(),
        wall_generate,
        wall_fleet,
        rayon::current_num_threads()
    );
    for v in &verdicts {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            v.robot,
            v.truth,
            v.found,
            v.rate_ratio.map(|q| format!("{q:.3}")).unwrap_or_default(),
            if v.correct { "yes" } else { "no" }
        ));
    }
    let json = FleetExperiment {
        robots: inp.runs,
        days: p.days,
        duration_s: p.duration_s,
        correct,
        wall_s_generate: wall_generate,
        wall_s_fleet: wall_fleet,
        threads: rayon::current_num_threads(),
        verdicts: &verdicts,
        truth: &truths,
    };
    Ok(ExperimentOutput::titled("Simulated fleet", md, &json))
}
