//! `odocal eval`: load an estimate and a reference (TUM, KITTI, or a bag's
//! reference topic) and/or relations, and evaluate.

use super::{Common, PipelineError};
use crate::error::InputError;
use crate::eval::{self, EvalOptions, EvalReport, Trajectory3};
use crate::io::{self, ReadOptions};
use std::path::{Path, PathBuf};

/// Loads a trajectory: an MCAP's reference stream (or, without one, its
/// odometry), a KITTI pose file when `times` is given, else a TUM file.
/// The flag is true for position-only sources: PointStamped references, or
/// orientations that are all the identity while the path turns
/// ([`Trajectory3::orientation_undefined`]).
pub fn load_trajectory(
    path: &Path,
    times: Option<&Path>,
    read: &ReadOptions,
) -> Result<(Trajectory3, bool), PipelineError> {
    let with_flag = |t: Trajectory3| {
        let undefined = t.orientation_undefined();
        (t, undefined)
    };
    if let Some(t) = times {
        return Ok(with_flag(io::kitti::read_kitti(path, t)?));
    }
    let file = path.display().to_string();
    if !io::sniff(path)?.is_bag() {
        return Ok(with_flag(io::tum::read_tum(path)?));
    }
    let rec = io::read_recording(path, read)?;
    let stream = if !rec.reference.is_empty() {
        &rec.reference
    } else {
        &rec.odom
    };
    let (traj, _repeated) = eval::trajectory_from_stamped(stream);
    if traj.len() < 2 {
        let topics = io::mcap_topics::trajectory_topics(path)?;
        let found: Vec<String> = topics
            .iter()
            .map(|(topic, ty)| format!("{ty} on {topic}"))
            .collect();
        let hint = match topics.first() {
            None => String::new(),
            Some((topic, _)) => format!(
                "; the bag holds {}: name the topic in a --config file, e.g. \
                 [topics] reference = \"{topic}\"",
                found.join(", ")
            ),
        };
        return Err(InputError::new(
            &file,
            format!(
                "no trajectory: topics {} and {} hold fewer than 2 poses{hint} (`odocal \
                 inspect {file}` lists the recording's pose topics)",
                read.topics.reference, read.topics.odom
            ),
        )
        .into());
    }
    let traj = Trajectory3::from_2d(&traj);
    let position_only = stream.iter().any(|s| !s.has_heading) || traj.orientation_undefined();
    Ok((traj, position_only))
}

/// What `odocal eval` is asked to do; every `None` keeps the configured
/// evaluation setting.
#[derive(Debug, Clone, Default)]
pub struct EvalJob {
    /// The trajectory under test.
    pub estimate: PathBuf,
    /// The reference trajectory.
    pub reference: Option<PathBuf>,
    /// Kümmerle et al. relations.
    pub relations: Option<PathBuf>,
    /// Timestamps of a KITTI estimate.
    pub estimate_times: Option<PathBuf>,
    /// Timestamps of a KITTI reference.
    pub reference_times: Option<PathBuf>,
    /// Alignment.
    pub align: Option<eval::Alignment>,
    /// Largest time difference for association (s).
    pub t_max_diff: Option<f64>,
    /// Offset added to the estimate's stamps (s).
    pub t_offset: Option<f64>,
    /// evo's interpolation within `t_max_diff`.
    pub interpolate: bool,
    /// Interpolate the reference at every estimate stamp (`None`: only for a
    /// position-only reference).
    pub resample: Option<bool>,
    /// Largest reference gap (s) resampling bridges.
    pub max_gap: Option<f64>,
    /// The RPE step.
    pub rpe_delta: Option<f64>,
    /// The RPE step's unit.
    pub rpe_unit: Option<eval::DeltaUnit>,
    /// The PNG to draw (needs a reference).
    pub plot: Option<PathBuf>,
    /// Configuration and robot files.
    pub common: Common,
}

impl EvalJob {
    /// The configured options with the job's choices.
    fn options(&self, mut opts: EvalOptions) -> EvalOptions {
        if let Some(al) = self.align {
            opts.align = al;
        }
        if let Some(t) = self.t_max_diff {
            opts.sync.max_diff = t;
        }
        if let Some(t) = self.t_offset {
            opts.sync.offset = t;
        }
        opts.sync.interpolate |= self.interpolate;
        if self.resample.is_some() {
            opts.sync.resample = self.resample;
        }
        if let Some(g) = self.max_gap {
            opts.sync.max_gap = g;
        }
        if let Some(d) = self.rpe_delta {
            opts.rpe_delta = eval::RpeDelta {
                value: d,
                unit: self.rpe_unit.unwrap_or(opts.rpe_delta.unit),
            };
        } else if let Some(u) = self.rpe_unit {
            opts.rpe_delta.unit = u;
        }
        opts
    }
}

/// Runs `odocal eval`: loads the estimate and the reference, evaluates, and
/// draws the plot when asked.
pub fn run(job: &EvalJob) -> Result<EvalReport, PipelineError> {
    if job.reference.is_none() && job.relations.is_none() {
        return Err(PipelineError::BadArgument(
            "eval needs --reference, --relations, or both".into(),
        ));
    }
    let inputs: Vec<&Path> = [
        Some(job.estimate.as_path()),
        job.reference.as_deref(),
        job.relations.as_deref(),
        job.estimate_times.as_deref(),
        job.reference_times.as_deref(),
    ]
    .into_iter()
    .flatten()
    .collect();
    let outputs: Vec<&Path> = job.plot.iter().map(PathBuf::as_path).collect();
    super::outputs::check_outputs(&inputs, &outputs)?;
    let _lock = super::outputs::lock_outputs(&outputs)?;
    let (cfg, robot) = job.common.load()?;
    let mut opts = job.options(cfg.eval);
    let read = super::read_options(&cfg, &robot);
    let (est, _) = load_trajectory(&job.estimate, job.estimate_times.as_deref(), &read)?;
    let reference = match &job.reference {
        Some(r) => {
            let (t, position_only) = load_trajectory(r, job.reference_times.as_deref(), &read)?;
            opts.position_only |= position_only;
            Some(t)
        }
        None => None,
    };
    if job.plot.is_some() && reference.is_none() {
        return Err(PipelineError::BadArgument(
            "--plot needs --reference".into(),
        ));
    }
    let report = evaluate(&est, reference.as_ref(), job.relations.as_deref(), &opts)?;
    if let Some(png) = &job.plot {
        write_plot(png, &report, opts.position_only)?;
    }
    Ok(report)
}

/// Evaluates `estimate` against `reference` and/or `relations`.
pub fn evaluate(
    estimate: &Trajectory3,
    reference: Option<&Trajectory3>,
    relations: Option<&Path>,
    opts: &EvalOptions,
) -> Result<EvalReport, PipelineError> {
    let rels = match relations {
        Some(p) => Some(io::relations::read_relations(p)?),
        None => None,
    };
    Ok(eval::evaluate(estimate, reference, rels.as_deref(), opts)?)
}

/// Writes `--plot`: the reference and the aligned estimate in the x–y plane
/// above the absolute errors over time (translation in m, rotation in deg
/// unless the reference is position-only), as one PNG. Needs a reference.
pub fn write_plot(
    path: &Path,
    report: &EvalReport,
    position_only: bool,
) -> Result<(), PipelineError> {
    use crate::viz::plot::{
        render_line_chart, render_trajectory_plot, LineChart, PathSeries, Rgb, Series,
        TrajectoryPlot,
    };
    let Some(d) = &report.detail else {
        return Err(PipelineError::BadArgument(
            "--plot needs a reference trajectory (--reference)".into(),
        ));
    };
    let xy = |poses: &[eval::Pose3]| -> Vec<[f64; 2]> {
        poses
            .iter()
            .map(|p| [p.translation.x, p.translation.y])
            .collect()
    };
    let viz_err = |e: crate::viz::VizError| PipelineError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let paths = vec![
        PathSeries::new("reference", xy(&d.matched.reference)).color([40, 40, 40]),
        PathSeries::new("estimate (aligned)", xy(&d.matched.estimate)).color([214, 39, 40]),
    ];
    let mut top = TrajectoryPlot::new(
        format!(
            "Estimate against reference: APE rmse {:.3} m over {} poses",
            d.ape.trans.rmse,
            d.matched.len()
        ),
        paths,
    );
    top.size = (1100, 800);
    let t0 = d.matched.ref_stamps.first().copied().unwrap_or(0.0);
    let t: Vec<f64> = d.matched.ref_stamps.iter().map(|s| s - t0).collect();
    let mut chart = LineChart::new(
        "Absolute pose error over time",
        "time from the first pose (s)",
    )
    .panel(
        "translation error (m)",
        vec![Series::from_xy("APE translation", &t, &d.ape.trans_errors)],
    );
    if !position_only {
        let deg: Vec<f64> = d.ape.rot_errors.iter().map(|r| r.to_degrees()).collect();
        chart = chart.panel(
            "rotation error (deg)",
            vec![Series::from_xy("APE rotation", &t, &deg)],
        );
    }
    let a = render_trajectory_plot(&top).map_err(viz_err)?;
    let b = render_line_chart(&chart).map_err(viz_err)?;
    Rgb::stack(&[a, b])
        .and_then(|img| img.save_png(path))
        .map_err(viz_err)
}
