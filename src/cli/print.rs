//! Human-readable output of each command (stdout, or stderr for the lines
//! that only say where the outputs went).

use odocal::calib::CalibSummary;
use odocal::icp::IcpStats;
use odocal::pipeline::demo::DemoSummary;
use odocal::pipeline::simulate::SimulateSummary;
use std::path::Path;

/// Prints a line on stdout; a closed pipe (`odocal ... | head`) is not an error.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}
pub(crate) use out;

pub fn relations(r: &odocal::eval::RelationStats) {
    let line = |name: &str, s: &odocal::eval::RelationSummary| {
        out!(
            "relations {name:<6} n={:<5} trans {:.3} ± {:.3} m   rot {:.2} ± {:.2} deg",
            s.count,
            s.trans_mean,
            s.trans_std,
            s.rot_mean_deg,
            s.rot_std_deg
        )
    };
    line("all", &r.all);
    if let Some(l) = &r.local {
        line("local", l);
    }
    if r.skipped > 0 {
        out!("relations skipped {} (outside the trajectory)", r.skipped);
    }
}

fn stats(name: &str, s: Option<&odocal::eval::Stats>) {
    match s {
        Some(s) => out!(
            "{name:<16} rmse {:.4}  mean {:.4}  median {:.4}  std {:.4}  min {:.4}  max {:.4}",
            s.rmse,
            s.mean,
            s.median,
            s.std,
            s.min,
            s.max
        ),
        None => out!("{name:<16} n/a (position-only reference)"),
    }
}

pub fn trajectory_metrics(t: &odocal::eval::TrajectoryMetrics) {
    out!(
        "paired poses     {} of {} ({}: {})",
        t.paired,
        t.of,
        t.pairing.method,
        t.pairing.reason
    );
    if 2 * t.paired < t.of {
        out!(
            "                 fewer than half of the poses paired: the streams are sampled at \
             different instants; try --resample-reference or a larger --t-max-diff"
        );
    }
    out!(
        "alignment        {} ({})",
        t.alignment.kind,
        t.alignment.reason
    );
    if t.alignment.kind.starts_with("sim") {
        out!(
            "scale            {:.4} (the reference's metric against the estimate's)",
            t.alignment.scale
        );
    }
    stats("APE (m)", Some(&t.ape));
    if t.ape_rot_deg.is_some() {
        stats("APE rot (deg)", t.ape_rot_deg.as_ref());
    }
    stats("RPE (m)", Some(&t.rpe));
    if t.rpe_rot_deg.is_some() {
        stats("RPE rot (deg)", t.rpe_rot_deg.as_ref());
    }
    if let Some(why) = &t.rotation_omitted {
        out!("rotation         not reported: {why}");
    }
    out!("RMSE x,y (m)     {:.4}", t.rmse_xy);
    if let Some(r) = t.rmse_theta {
        out!("RMSE θ (rad)     {r:.4}");
    }
    match t.drift_percent {
        Some(d) => out!("drift            {d:.3} % of {:.1} m", t.path_length),
        None => out!("drift            n/a (reference does not move)"),
    }
    out!("final error (m)  {:.4}", t.final_error);
}

pub fn calibration(s: &CalibSummary, out: &Path) {
    assumptions(&s.assumptions);
    wheel_source(s);
    if let Some(b) = &s.batch {
        return batch(s, b, out);
    }
    if let Some(o) = &s.observability {
        observability(o);
    }
    if let Some(b) = &s.start {
        eprintln!(
            "started from the batch estimate: R_R {:.5} m, R_L {:.5} m, D {:.5} m",
            b.r_right.value, b.r_left.value, b.wheel_base.value
        );
        for n in &b.notes {
            eprintln!("batch note: {n}");
        }
    }
    eprintln!(
        "{}: R_R {:.5} ± {:.5} m, R_L {:.5} ± {:.5} m, D {:.5} ± {:.5} m after {} steps ({:.3} ms/step)",
        s.method,
        s.final_params.r_right,
        s.std.r_right,
        s.final_params.r_left,
        s.std.r_left,
        s.final_params.wheel_base,
        s.std.wheel_base,
        s.iterations,
        s.mean_iteration_ms
    );
    eprintln!(
        "diff_drive_controller multipliers: right_wheel_radius {:.5}, left_wheel_radius {:.5}, wheel_separation {:.5}; outputs in {}",
        s.multipliers.right_wheel_radius,
        s.multipliers.left_wheel_radius,
        s.multipliers.wheel_separation,
        out.display()
    );
}

/// What to paste: the ros2_control YAML and the laser mounting snippets.
pub fn paste(p: &odocal::pipeline::paste::Paste, out: &Path) {
    eprintln!(
        "ros2_control parameters ({}):",
        out.join(odocal::pipeline::paste::YAML_FILE).display()
    );
    for l in p.ros2_control.yaml.lines().filter(|l| !l.starts_with('#')) {
        out!("{l}");
    }
    if let Some(l) = &p.laser_mount {
        eprintln!(
            "laser mounting ({}):",
            out.join(odocal::pipeline::paste::URDF_FILE).display()
        );
        out!("{}", l.urdf.trim_end());
        out!("{}", l.static_transform);
    }
}

/// The batch estimate: every unknown with its std and observability.
fn batch(s: &CalibSummary, b: &odocal::calib::batch::BatchEstimate, out: &Path) {
    let obs = s.observability.as_ref();
    let line = |name: &str, v: odocal::calib::batch::Valued, unit: &str| {
        let note = obs
            .and_then(|o| o.parameters.get(name))
            .map(|p| match (p.weak, p.missing.as_deref()) {
                (true, Some(m)) => format!(" (weakly observable: {m})"),
                _ => " (observable)".to_string(),
            })
            .unwrap_or_default();
        out!("{name:<12} {:>12.6} ± {:.6} {unit}{note}", v.value, v.std);
    };
    if let Some(o) = obs {
        let e = &o.excitation;
        eprintln!(
            "excitation: {} intervals, {:.2} m driven ({:.2} m straight), turns {:.2} rad left / {:.2} rad right",
            e.steps, e.distance_m, e.straight_m, e.turn_left_rad, e.turn_right_rad
        );
    }
    out!(
        "batch: {} intervals ({} dropped as outliers), χ² {:.1} for {} degrees of freedom",
        b.intervals,
        b.dropped,
        b.chi2,
        b.dof
    );
    line("r_right", b.r_right, "m");
    line("r_left", b.r_left, "m");
    line("wheel_base", b.wheel_base, "m");
    line("laser_x", b.laser.x, "m");
    line("laser_y", b.laser.y, "m");
    line("laser_yaw", b.laser.yaw, "rad");
    match b.time_offset {
        Some(t) => line("time_offset", t, "s"),
        None => out!("time_offset  not estimated (the input carries no wheel time, or [calib.batch] time_offset = false)"),
    }
    for n in &b.notes {
        out!("note: {n}");
    }
    eprintln!(
        "diff_drive_controller multipliers: right_wheel_radius {:.5}, left_wheel_radius {:.5}, wheel_separation {:.5}; summary in {}",
        s.multipliers.right_wheel_radius,
        s.multipliers.left_wheel_radius,
        s.multipliers.wheel_separation,
        out.join("summary.json").display()
    );
}

/// The demo's summary, and where its report and recording are.
pub fn demo(summary: &DemoSummary, out: &Path, to_file: bool) {
    assumptions(&summary.assumptions);
    out!(
        "odocal demo on {} ({} scans, {:.0} s) in {:.1} s",
        summary.input,
        summary.scans,
        summary.duration_s,
        summary.wall_s
    );
    out!(
        "ICP: {} pairs, {} flagged, {:.1} iterations on average",
        summary.icp.pairs,
        summary.icp.failed_pairs,
        summary.icp.mean_iterations
    );
    for m in &summary.methods {
        let err = m
            .final_errors
            .map(|e| {
                format!(
                    "  error R_R {:+.2} mm, R_L {:+.2} mm, D {:+.1} mm",
                    e[0] * 1e3,
                    e[1] * 1e3,
                    e[2] * 1e3
                )
            })
            .unwrap_or_default();
        let ape = m
            .eval
            .as_ref()
            .map(|e| format!("  APE {:.3} m", e.ape.rmse))
            .unwrap_or_default();
        out!(
            "{:<12} R_R {:.5} m  R_L {:.5} m  D {:.4} m{err}{ape}",
            m.method,
            m.final_params[0],
            m.final_params[1],
            m.final_params[2]
        );
    }
    for note in &summary.eval_notes {
        out!("note: {note}");
    }
    out!("report: {}", out.join("report.md").display());
    if cfg!(feature = "rerun") && to_file {
        out!(
            "open the recording with: rerun {}",
            out.join("demo.rrd").display()
        );
    }
}

/// What `odocal simulate` wrote.
pub fn simulation(summary: &SimulateSummary) {
    eprintln!(
        "wrote {} ({} scans, {:.0} s, {:.1} m of {}){}",
        summary.out,
        summary.scans,
        summary.duration_s,
        summary.path_length_m,
        summary.scenario,
        summary
            .truth
            .as_deref()
            .map(|t| format!("; truth in {t}"))
            .unwrap_or_default()
    );
}

/// Where the wheels came from and what that source cannot show; with the
/// robot's own odometry as the source, how far it is off in scale.
fn wheel_source(s: &CalibSummary) {
    let Some(w) = &s.wheel_source else {
        return;
    };
    eprintln!("{}", w.sentence());
    for n in &w.notes {
        eprintln!("note: {n}");
    }
    if let Some(o) = &s.odometry_scale {
        eprintln!(
            "the robot's own odometry: true distance = {:.5} × its distance, true turn = {:.5} × its turn (odometry_scale)",
            o.linear,
            o.angular
        );
    }
}

/// Where each nominal value came from, one line each.
pub fn assumptions(a: &odocal::assumptions::Assumptions) {
    for line in a.lines() {
        eprintln!("assuming {line}");
    }
}

/// Each parameter's observability, and what the run's motion lacked.
pub fn observability(o: &odocal::calib::Observability) {
    let e = &o.excitation;
    eprintln!(
        "excitation: {} steps, {:.2} m driven ({:.2} m straight), turns {:.2} rad left / {:.2} rad right, up to {:.2} m/s",
        e.steps, e.distance_m, e.straight_m, e.turn_left_rad, e.turn_right_rad, e.speed_max
    );
    for (name, p) in &o.parameters {
        if p.weak {
            eprintln!(
                "warning: {name} is weakly determined ({}); its std is widened to {:.5} m",
                p.missing.as_deref().unwrap_or(""),
                p.std
            );
        }
    }
}

/// What `odocal icp` matched and wrote.
pub fn icp(stats: &IcpStats, path_length: f64, out: &Path, prior: &odocal::icp::Prior) {
    eprintln!(
        "{} pairs ({} failed), {:.1} iterations on average, {:.2} s ({:.0} pairs/s); trajectory {:.1} m -> {}",
        stats.pairs,
        stats.failed_pairs,
        stats.mean_iterations,
        stats.wall_s,
        stats.pairs_per_s,
        path_length,
        out.display()
    );
    if let Some(f) = &stats.prior_time_offset {
        prior_clock(f);
    }
    if let Some(s) = &stats.prior_scale {
        prior_scale(s, prior);
    }
}

/// The prior's scale check of `odocal icp`: its distances and turns against
/// the matched ones, and what a ratio far from 1 means for this prior.
fn prior_scale(s: &odocal::icp::PriorScale, prior: &odocal::icp::Prior) {
    let ratio = |r: Option<f64>| r.map_or("not measured".to_string(), |r| format!("{r:.2}×"));
    eprintln!(
        "odometry scale: its distances are {} the matched ones, its turns {} ({} pairs the scans \
         measured: {:.1} m, {:.1} rad)",
        ratio(s.distance_ratio),
        ratio(s.turn_ratio),
        s.pairs,
        s.distance_m,
        s.turn_rad
    );
    if !s.off() {
        return;
    }
    let why = match prior {
        odocal::icp::Prior::Wheels(_) => {
            "the wheel radii and wheel base the prior is integrated with (stated above) are not \
             this robot's: give --robot ROBOT.toml with its own (calibrate estimates them from there)"
        }
        _ => "the recording's odometry and the scans disagree in scale (its own calibration, or \
              a laser mounting that is not the stated one)",
    };
    eprintln!("  the prior's scale is not the scans': {why}");
}

/// The prior's clock check of `odocal icp`: the offset in use, where the
/// odometry's turns fit the matched ones best, and what to set when the two
/// disagree.
fn prior_clock(f: &odocal::icp::TimeOffsetFit) {
    eprintln!(
        "odometry clock: offset {:+.3} s in use (odometry stamp − laser stamp); its turns fit the \
         matched ones best at {:+.3} s{} (heading increments {:.4} rad RMS per pair there, {:.4} \
         at the offset in use; {} pairs)",
        f.used_s,
        f.best_s,
        if f.at_edge {
            ", the edge of the offsets tried"
        } else {
            ""
        },
        f.rms_best_rad,
        f.rms_used_rad,
        f.pairs
    );
    if f.contradicts_used() {
        eprintln!(
            "  the scans and the odometry disagree in time: set [icp] time_offset = {:.2} in a \
             --config file to read the prior at that offset (with wheel encoders, calibrate \
             --method batch estimates it with its std)",
            f.best_s
        );
    }
}
