//! What changed at a firing of the change detector, through the whole chain:
//! `odocal simulate` with a known change → `odocal calibrate` (ICP on the
//! simulated scans, the Adaptive-PF and its detector) → the named change in
//! `--json`, `summary.json` and the history's `change` column, against the
//! simulator's truth.

use crate::support::{odocal, scratch};
use std::path::Path;

/// `odocal simulate ARGS` with `effect` (none when empty) into `dir`/run.mcap;
/// `odocal calibrate --json` of it into `dir`/cal. Returns the `--json`
/// output (the same `changes` as `summary.json`) and the history CSV.
fn simulated_and_calibrated(
    dir: &Path,
    args: &[&str],
    effect: &str,
) -> (serde_json::Value, String) {
    let bag = dir.join("run.mcap");
    let mut sim = vec!["simulate", "--out", bag.to_str().unwrap()];
    sim.extend(args);
    if !effect.is_empty() {
        sim.extend(["--effect", effect]);
    }
    let s = odocal(&sim);
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let out = dir.join("cal");
    let json = calibrate(&bag, &out);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["changes"], summary["changes"]);
    let csv = std::fs::read_to_string(out.join("calibration.csv")).unwrap();
    (json, csv)
}

/// Simulates 60 s (seed 2) with `effect` (none when empty), calibrates,
/// returns the `--json` output and the history CSV.
fn run(dir: &Path, effect: &str) -> (serde_json::Value, String) {
    let truth = dir.join("truth.json");
    let args = [
        "--seed",
        "2",
        "--duration",
        "60",
        "--truth",
        truth.to_str().unwrap(),
    ];
    simulated_and_calibrated(dir, &args, effect)
}

/// `odocal calibrate --json` of `bag` into `out`.
fn calibrate(bag: &Path, out: &Path) -> serde_json::Value {
    let c = odocal(&[
        "calibrate",
        "--input",
        bag.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    serde_json::from_slice(&c.stdout).unwrap()
}

/// The `change` column's non-empty entries, with their row's time.
fn named_rows(csv: &str) -> Vec<(f64, String)> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.last(), Some(&"change"));
    assert_eq!(
        header[..9].join(","),
        "t,r_right,r_left,wheel_base,std_r_right,std_r_left,std_wheel_base,particles,process_sigma"
    );
    lines
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), header.len(), "{l}");
            (!f[9].is_empty()).then(|| (f[0].parse().unwrap(), f[9].to_string()))
        })
        .collect()
}

#[test]
fn a_radius_step_on_the_right_wheel_is_named_with_its_size() {
    let d = scratch("change-naming-step");
    let truth = 0.005;
    let (json, csv) = run(&d, &format!("radius_step:time=30,right={truth},left=0"));
    let changes = json["changes"].as_array().expect("the detector fired");
    let first = &changes[0];
    assert_eq!(first["effect"], "radius_step", "{first}");
    // Named against a converged filter, which tells the wheel.
    assert_eq!(first["baseline"], "converged", "{first}");
    assert_eq!(first["parameter"], "right", "{first}");
    let est = first["estimate"].as_f64().unwrap();
    assert!(
        (est - truth).abs() < 0.2 * truth,
        "step {est} m vs {truth} m"
    );
    let se = first["stderr"].as_f64().unwrap();
    assert!(se > 0.0 && se < 0.2 * truth, "stderr {se}");
    assert!(first["delta_bic"].as_f64().unwrap() > 10.0);
    // The left wheel did not change: its size is small against the right's.
    let left = first["parameters"]["left"].as_f64().unwrap();
    assert!(left.abs() < 0.2 * truth, "left {left}");
    // The detector fires after the step, within the window.
    let t = first["time_s"].as_f64().unwrap();
    assert!((30.0..40.0).contains(&t), "fired at {t} s");
    let onset = first["onset_s"].as_f64().unwrap();
    assert!((onset - 30.0).abs() < 1.0, "onset {onset} s");
    let rows = named_rows(&csv);
    assert_eq!(rows.len(), changes.len());
    assert!((rows[0].0 - t).abs() < 1e-6 && rows[0].1 == "radius_step");
}

/// A step 20 s into a corridor run, as the filters begin: the estimate at
/// the start of its window is still spreading from the front end's start
/// (radius std 0.8–5 % of the radius), and against it the step came out on
/// the wrong wheel (left +5.8 mm where the right changed by −5 mm and the
/// left by +4 mm). It is named `radius_step` against an `unconverged`
/// baseline and names no wheel; the step at 30 s above, against a converged
/// one, names it (the negative control).
#[test]
fn a_step_named_against_an_unconverged_filter_names_no_wheel() {
    let d = scratch("change-naming-unconverged");
    let bag = d.join("run.mcap");
    let out = d.join("cal");
    let s = odocal(&[
        "simulate",
        "--scenario",
        "corridor-loop",
        "--seed",
        "11",
        "--duration",
        "70",
        "--effect",
        "radius_step:time=20,right=-0.005,left=0.004",
        "--out",
        bag.to_str().unwrap(),
    ]);
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let json = calibrate(&bag, &out);
    let changes = json["changes"].as_array().expect("the detector fired");
    let steps: Vec<&serde_json::Value> = changes
        .iter()
        .filter(|c| c["effect"] == "radius_step")
        .collect();
    assert!(!steps.is_empty(), "{changes:?}");
    for c in steps {
        assert_eq!(c["baseline"], "unconverged", "{c}");
        assert!(c["baseline_rel_std"].as_f64().unwrap() > 0.005, "{c}");
        assert_eq!(c["parameter"], "", "a wheel named: {c}");
        // The fit's sizes stay, for what they are worth.
        assert!(c["parameters"]["right"].is_number(), "{c}");
    }
}

/// A latency that appears during the run (at 15 s, before the robot turns)
/// is a change of the clocks, which the online front end follows: its fits
/// of the time offset find the new latency (the last fit within 20 ms of
/// 0.08 s, where the start's 0 fails), and the filters' detector never
/// names it a radius step. (One that appears at 25 s, on a straight
/// stretch, is not found by the end of this 60 s run: the window of the
/// fits reaches back over the 25 s without it, and the heading the offset
/// shows in comes only with the turns from 38 s on.)
#[test]
fn a_latency_change_is_followed_by_the_time_offset_not_named_a_radius_step() {
    let at = 15;
    let d = scratch(&format!("change-naming-latency-{at}"));
    let (json, csv) = run(&d, &format!("latency_change:time={at},delay=0.08"));
    for c in json["changes"].as_array().into_iter().flatten() {
        assert_ne!(c["effect"], "radius_step", "at {at} s: {c}");
    }
    assert!(!named_rows(&csv).iter().any(|r| r.1 == "radius_step"));
    let fits = json["solves"].as_array().unwrap();
    let last = fits
        .iter()
        .rev()
        .find_map(|f| f["time_offset"]["value"].as_f64())
        .expect("a fit");
    crate::support::assert_recovered("latency", last, 0.08, 0.0, 0.02);
}

#[test]
fn a_knocked_laser_is_named_a_mounting_change_with_its_turn() {
    let d = scratch("change-naming-knock");
    let (json, csv) = run(&d, "laser_knock:time=30,dx=0,dy=0,dyaw=0.035");
    let changes = json["changes"]
        .as_array()
        .expect("the mounting watch fired");
    assert_eq!(changes.len(), 1, "{changes:?}");
    let c = &changes[0];
    assert_eq!(c["detector"], "laser_mount", "{c}");
    assert_eq!(c["effect"], "laser_offset", "{c}");
    assert_eq!(c["parameter"], "yaw", "{c}");
    // The turn within 20 % of the knock's; the mount left as it was (no
    // turn) misses by five times that and must fail the same check.
    let yaw = c["estimate"].as_f64().unwrap();
    crate::support::assert_recovered("knocked yaw (rad)", yaw, 0.035, 0.0, 0.2 * 0.035);
    for k in ["x", "y"] {
        let v = c["parameters"][k].as_f64().unwrap();
        assert!(v.abs() < 0.02, "{k} {v} m");
    }
    let onset = c["onset_s"].as_f64().unwrap();
    assert!((onset - 30.0).abs() < 1.0, "onset {onset} s");
    // The filter's detector did not fire: the history names the mounting
    // change once, at the first row at or after the firing.
    let t = c["time_s"].as_f64().unwrap();
    let rows = named_rows(&csv);
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert_eq!(rows[0].1, "laser_offset");
    assert!(
        rows[0].0 >= t && rows[0].0 < t + 1.0,
        "row {} vs {t} s",
        rows[0].0
    );
}

/// Whether a calibration's `--json` and history name no change: every
/// firing of the detector (a non-empty `change` cell of the history) has
/// its entry in `changes`, and each says `undetermined`. The key is left
/// out only when the detector never fired; left out after a firing it is
/// an error, not an empty list.
fn nothing_named(json: &serde_json::Value, csv: &str) -> Result<(), String> {
    let rows = named_rows(csv);
    let changes = match json.get("changes") {
        None if rows.is_empty() => return Ok(()),
        None => return Err(format!("history rows {rows:?} but no `changes`")),
        Some(c) => c
            .as_array()
            .ok_or(format!("`changes` is not a list: {c}"))?,
    };
    if changes.len() != rows.len() {
        return Err(format!("{} changes, history rows {rows:?}", changes.len()));
    }
    match changes.iter().find(|c| c["effect"] != "undetermined") {
        Some(c) => Err(format!("named: {c}")),
        None if rows.iter().any(|r| r.1 != "undetermined") => Err(format!("rows {rows:?}")),
        None => Ok(()),
    }
}

#[test]
fn nothing_is_named_on_a_run_where_nothing_changed() {
    let d = scratch("change-naming-null");
    let (json, csv) = run(&d, "");
    eprintln!(
        "changes: {}",
        json.get("changes").unwrap_or(&"absent".into())
    );
    nothing_named(&json, &csv).unwrap();
    // The same check fails a run where the detector fired and named a step
    // (in the history and in `changes`), and one whose history shows a
    // firing that `changes` leaves out.
    let mut fired_csv = csv.trim_end().to_string();
    fired_csv.push_str("radius_step\n");
    let mut named = json.clone();
    named["changes"] = serde_json::json!([{ "effect": "radius_step" }]);
    assert!(nothing_named(&named, &fired_csv).is_err());
    let mut dropped = named;
    dropped.as_object_mut().unwrap().remove("changes");
    assert!(nothing_named(&dropped, &fired_csv).is_err());
}

/// `odocal calibrate --json` of a `secs` s simulated run of `scenario` and
/// `seed` with `effect` (none when empty), and its history.
fn scenario_run(
    scenario: &str,
    seed: &str,
    secs: &str,
    effect: &str,
) -> (serde_json::Value, String) {
    let d = scratch(&format!(
        "change-naming-{scenario}-{seed}-{}",
        effect.is_empty()
    ));
    let args = ["--scenario", scenario, "--seed", seed, "--duration", secs];
    simulated_and_calibrated(&d, &args, effect)
}

/// The filters start from a cloud ±10 % wide and converge during the run's
/// first seconds; the wheel base all at once when the robot first turns.
/// On these null runs the detector fires as they do (the square at its
/// first turn in place, 11.5 s, on every seed tried; the corridor loop at
/// 18 s): its window holds innovations read against means the cloud has
/// since left. The filter re-spreads (`respreads_s`), but each measurement
/// read against its own step's belief shows no change, and none is
/// reported (before that reading both were reported as `undetermined`
/// changes). The negative control: the same square with the right radius
/// 5 mm larger from 25 s reports a change.
#[test]
fn a_filter_converging_re_spreads_itself_and_reports_no_change() {
    for (scenario, seed, secs) in [("square", "21", "40"), ("corridor-loop", "13", "30")] {
        let (json, csv) = scenario_run(scenario, seed, secs, "");
        assert!(
            json.get("changes").is_none(),
            "{scenario}: {}",
            json["changes"]
        );
        assert!(named_rows(&csv).is_empty(), "{scenario}");
        let spread = json["respreads_s"].as_array().expect("the detector fired");
        assert!(!spread.is_empty(), "{scenario}");
    }
    let (json, csv) = scenario_run(
        "square",
        "21",
        "45",
        "radius_step:time=25,right=0.005,left=0",
    );
    let rows = named_rows(&csv);
    assert!(
        !rows.is_empty() && json.get("changes").is_some(),
        "the step went unnoticed"
    );
    assert!(
        rows[0].0 > 25.0,
        "reported at {} s, before the step",
        rows[0].0
    );
}

/// A logger that keeps the text entries of what changed and the stamps of
/// the estimates.
#[derive(Default)]
struct Notes {
    changes: Vec<(i64, f64, String)>,
    estimates: Vec<(i64, f64)>,
}

impl odocal::viz::Logger for Notes {
    fn map(&mut self, _: &[[nalgebra::Point2<f64>; 2]]) -> Result<(), odocal::viz::VizError> {
        Ok(())
    }
    fn scan(
        &mut self,
        _: odocal::viz::Stamp,
        _: &odocal::geom::Pose2,
        _: &odocal::geom::Pose2,
        _: &[nalgebra::Point2<f64>],
    ) -> Result<(), odocal::viz::VizError> {
        Ok(())
    }
    fn trajectory(
        &mut self,
        _: odocal::viz::TrajectoryKind,
        _: &[f64],
        _: &[odocal::geom::Pose2],
    ) -> Result<(), odocal::viz::VizError> {
        Ok(())
    }
    fn particles(
        &mut self,
        _: odocal::viz::Stamp,
        _: &[f64],
        _: &[f64],
        _: &[f64],
    ) -> Result<(), odocal::viz::VizError> {
        Ok(())
    }
    fn estimate(
        &mut self,
        at: odocal::viz::Stamp,
        _: &odocal::viz::CalibEstimate,
    ) -> Result<(), odocal::viz::VizError> {
        self.estimates.push((at.scan, at.time));
        Ok(())
    }
    fn icp(&mut self, _: odocal::viz::Stamp, _: u32, _: f64) -> Result<(), odocal::viz::VizError> {
        Ok(())
    }
    fn change(&mut self, at: odocal::viz::Stamp, text: &str) -> Result<(), odocal::viz::VizError> {
        self.changes.push((at.scan, at.time, text.to_string()));
        Ok(())
    }
    fn finish(&mut self) -> Result<(), odocal::viz::VizError> {
        Ok(())
    }
}

/// Simulates 60 s with `effect` (seed `seed`) and calibrates it, the
/// history's firings named and the run recorded into a [`Notes`]; returns
/// the changes named and what the recording logged.
fn recorded(
    effect: &str,
    seed: u64,
    dir: &str,
) -> (Vec<odocal::diagnose::onset::NamedChange>, Notes) {
    use odocal::pipeline::observe::Observers;
    use odocal::pipeline::outputs::CalibFiles;
    use odocal::pipeline::recorder::{RecorderOptions, StreamRecorder};
    let robot = odocal::robot::RobotConfig::default();
    let cfg = odocal::pipeline::Config::load(None).unwrap();
    // A fault (a knocked laser) or a departure of the model.
    let fault = odocal::effects::FaultEffect::parse(effect).ok();
    let sim = odocal::sim::SimConfig {
        duration_s: 60.0,
        seed,
        faults: fault.into_iter().collect(),
        ..Default::default()
    };
    let effects: Vec<_> = odocal::effects::Effect::parse(effect)
        .ok()
        .into_iter()
        .collect();
    let (rec, _) = odocal::sim::simulate(&sim, &robot, &effects, &mut |_| {}).unwrap();
    let params = odocal::pipeline::calibrate::params_for_robot(&cfg.calib, &robot);
    let mut notes = Notes::default();
    let mut files = CalibFiles::create(&scratch(dir))
        .unwrap()
        .naming_changes(&robot, &params.change.naming);
    let mut recorder = StreamRecorder::new(
        &mut notes,
        RecorderOptions::default(),
        robot.diff_drive(),
        robot.laser.unwrap().pose(),
    );
    let mut source = odocal::io::RecordingSource::new(&rec);
    odocal::pipeline::drive::run_calibration(
        &mut source,
        &robot,
        &cfg.icp,
        &params,
        &cfg.measurements,
        &mut Observers(vec![&mut recorder, &mut files]),
    )
    .unwrap();
    let changes = files.changes();
    let at: Vec<(f64, String)> = changes
        .iter()
        .map(|c| (c.time_s, odocal::pipeline::changes::describe(c)))
        .collect();
    recorder.changes(&at);
    recorder.finish().unwrap();
    (changes, notes)
}

#[test]
fn the_recording_carries_what_changed_at_the_firing() {
    let (changes, notes) = recorded(
        "radius_step:time=30,right=0,left=0.005",
        4,
        "change_naming_recorder",
    );
    assert!(!changes.is_empty(), "the detector fired");
    assert_eq!(changes[0].effect, "radius_step");
    assert_eq!(changes[0].parameter, "left");
    assert_eq!(notes.changes.len(), changes.len());
    let (scan, time, text) = &notes.changes[0];
    assert!(text.contains("radius_step left"), "{text}");
    // At the estimate of the step that fired, on both timelines (the
    // recording's time starts at its first sample).
    let at = notes
        .estimates
        .iter()
        .find(|e| e.1 == *time)
        .expect("an estimate at the firing's time");
    assert_eq!(at.0, *scan);
    assert!(
        (time - changes[0].time_s).abs() < 0.5,
        "{time} vs {}",
        changes[0].time_s
    );
}

#[test]
fn the_recording_carries_a_knocked_laser_at_its_firing() {
    let (changes, notes) = recorded(
        "laser_knock:time=30,dx=0,dy=0,dyaw=0.035",
        2,
        "change_naming_recorder_knock",
    );
    let mount: Vec<_> = changes
        .iter()
        .filter(|c| c.detector == odocal::diagnose::onset::MOUNT)
        .collect();
    assert_eq!(mount.len(), 1, "{changes:?}");
    let texts: Vec<_> = notes
        .changes
        .iter()
        .filter(|c| c.2.contains("laser-mounting watch"))
        .collect();
    assert_eq!(texts.len(), 1, "{:?}", notes.changes);
    let (scan, time, text) = texts[0];
    assert!(text.contains("laser_offset yaw"), "{text}");
    // At the estimate of the first step at or after the firing: the
    // recording's time starts at its first sample, the firing's is the
    // sensor's; the simulated run starts at 0 s.
    let first = notes
        .estimates
        .iter()
        .find(|e| e.1 >= mount[0].time_s - 1e-9)
        .expect("a step after the firing");
    assert_eq!((first.0, first.1), (*scan, *time));
    assert!(
        (time - mount[0].time_s).abs() < 1.0,
        "{time} vs {}",
        mount[0].time_s
    );
}
