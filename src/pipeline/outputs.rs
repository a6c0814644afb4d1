//! The observers that keep a run's results: the output files, written row by
//! row as the run goes and committed atomically only when it succeeded
//! ([`IcpFiles`], [`CalibFiles`]), and the results in memory ([`Collect`]);
//! and the check every command makes of its output paths before any work
//! ([`check_outputs`]) and the lock it holds on them while it runs
//! ([`lock_outputs`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use super::observe::RunObserver;
use super::PipelineError;
use crate::calib::{CalibSummary, CalibrationRun, CloudView, Estimate};
use crate::geom::Pose2;
use crate::icp::IcpStats;
use crate::io::out_lock::{LockError, OutputLock};
use crate::io::stream_out::AtomicWriter;
use crate::motion::{Motion, VelocityObs};
use crate::traj::Trajectory;

/// Checks a command's inputs and output paths before it does any work: every
/// input must be a regular file ([`crate::io::input::check_regular`]); no
/// output may be (or link to) one of its inputs or another of its outputs,
/// and none may name anything but a regular file (a directory, device or
/// pipe is refused; a symbolic link is written through). Each refusal names
/// the path.
pub fn check_outputs(inputs: &[&Path], outputs: &[&Path]) -> Result<(), PipelineError> {
    for input in inputs {
        crate::io::input::check_regular(input)?;
    }
    let mut seen: Vec<(&Path, FileId)> = Vec::new();
    for input in inputs {
        if let Some(id) = FileId::of(input) {
            seen.push((input, id));
        }
    }
    let n_inputs = seen.len();
    for out in outputs {
        let target = crate::io::atomic::target_of(out)
            .map_err(|e| PipelineError::BadArgument(format!("output {}: {e}", out.display())))?;
        let Some(id) = FileId::of(&target) else {
            continue;
        };
        if let Some((i, (other, _))) = seen.iter().enumerate().find(|(_, (_, s))| *s == id) {
            let what = if i < n_inputs {
                "the input"
            } else {
                "the output"
            };
            return Err(PipelineError::BadArgument(format!(
                "output {} is {what} {}: odocal never writes over a file it reads or writes \
                 twice; choose another output path",
                out.display(),
                other.display()
            )));
        }
        seen.push((out, id));
    }
    Ok(())
}

/// Locks each output (a file, or the directory of an output set) for the
/// run: while the returned guards live, another odocal run on the same output
/// is refused with exit 2 naming the lock, so the files of two runs never
/// mix. Call after [`check_outputs`], before anything is written.
pub fn lock_outputs(outputs: &[&Path]) -> Result<Vec<OutputLock>, PipelineError> {
    outputs
        .iter()
        .map(|out| {
            OutputLock::acquire(out).map_err(|e| match e {
                LockError::Busy { .. } => PipelineError::BadArgument(format!(
                    "output {} is being written: {e}; wait for that run to end or choose \
                     another output",
                    out.display()
                )),
                LockError::Io(..) => PipelineError::write(out, e),
            })
        })
        .collect()
}

/// What identifies a file whatever the path that names it: device and inode
/// on Unix (the canonical path elsewhere) when it exists; when it does not
/// yet, its canonical directory and name. `None` when neither can be told.
#[derive(Debug, Clone, PartialEq, Eq)]
enum FileId {
    Existing(String),
    ToBe(PathBuf),
}

impl FileId {
    fn of(path: &Path) -> Option<Self> {
        let Ok(meta) = std::fs::metadata(path) else {
            let dir = match path.parent().filter(|d| !d.as_os_str().is_empty()) {
                Some(d) => std::fs::canonicalize(d).ok()?,
                None => std::env::current_dir().ok()?,
            };
            return Some(Self::ToBe(dir.join(path.file_name()?)));
        };
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            Some(Self::Existing(format!("{}:{}", meta.dev(), meta.ino())))
        }
        #[cfg(not(unix))]
        {
            let _ = meta;
            Some(Self::Existing(
                std::fs::canonicalize(path).ok()?.display().to_string(),
            ))
        }
    }
}

/// A text file written line by line, keeping its first write error.
struct RowFile {
    out: AtomicWriter,
    path: PathBuf,
    error: Option<std::io::Error>,
}

impl RowFile {
    /// Starts `path` with the `header` line.
    fn create(path: &Path, header: &str) -> Result<Self, PipelineError> {
        let mut out = AtomicWriter::create(path).map_err(|e| PipelineError::write(path, e))?;
        writeln!(out.writer(), "{header}").map_err(|e| PipelineError::write(path, e))?;
        Ok(Self {
            out,
            path: path.to_path_buf(),
            error: None,
        })
    }

    /// Writes with `f` unless an earlier write failed.
    fn row(
        &mut self,
        f: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
    ) {
        if self.error.is_none() {
            if let Err(e) = f(self.out.writer()) {
                self.error = Some(e);
            }
        }
    }

    /// Renames the finished file over its path, or reports the first error.
    fn commit(self) -> Result<(), PipelineError> {
        if let Some(e) = self.error {
            return Err(PipelineError::write(&self.path, e));
        }
        self.out
            .commit()
            .map_err(|e| PipelineError::write(&self.path, e))
    }
}

/// A TUM trajectory file written pose by pose; poses whose stamp is not
/// finite or does not increase are left out, as [`Trajectory::push`] does.
struct TumFile {
    file: RowFile,
    last: Option<f64>,
}

impl TumFile {
    fn create(path: &Path) -> Result<Self, PipelineError> {
        Ok(Self {
            file: RowFile::create(path, crate::io::tum::TUM_HEADER)?,
            last: None,
        })
    }

    fn pose(&mut self, t: f64, p: &Pose2) {
        if t.is_finite() && self.last.is_none_or(|l| t > l) {
            self.last = Some(t);
            self.file.row(|w| crate::io::tum::write_pose_2d(w, t, p));
        }
    }
}

/// `odocal icp`'s files: the ICP trajectory (TUM) and, if asked, the motions
/// with covariance and quality (CSV).
pub struct IcpFiles {
    trajectory: TumFile,
    motions: Option<RowFile>,
}

impl IcpFiles {
    /// Starts writing `tum` and, if given, `motions_csv`.
    pub fn create(tum: &Path, motions_csv: Option<&Path>) -> Result<Self, PipelineError> {
        Ok(Self {
            trajectory: TumFile::create(tum)?,
            motions: motions_csv
                .map(|p| RowFile::create(p, crate::io::csv::MOTIONS_HEADER))
                .transpose()?,
        })
    }

    /// Commits every file of a run that succeeded.
    pub fn commit(self) -> Result<(), PipelineError> {
        self.trajectory.file.commit()?;
        self.motions.map_or(Ok(()), RowFile::commit)
    }
}

impl RunObserver for IcpFiles {
    fn icp_pose(&mut self, t: f64, pose: &Pose2) {
        self.trajectory.pose(t, pose);
    }

    fn motion(&mut self, motion: &Motion) {
        if let Some(f) = self.motions.as_mut() {
            f.row(|w| crate::io::csv::write_motion_row(w, motion));
        }
    }
}

/// `odocal calibrate`'s files in `DIR`: `calibration.csv` (the estimate after
/// every step), `trajectory.tum` (the calibrated odometry) and, at commit,
/// `summary.json`.
pub struct CalibFiles {
    dir: PathBuf,
    history: RowFile,
    trajectory: TumFile,
    /// Names what changed at each firing of the change detector (when
    /// naming is on).
    watch: Option<super::changes::ChangeWatch>,
    /// History rows not yet written: (time (s), fields, whether the filter's
    /// detector fired there). A row is written once its `change` cell is
    /// known: its filter firing named, and every laser-mounting firing that
    /// can still be dated at or before it named.
    held: std::collections::VecDeque<(f64, crate::io::csv::HistoryFields, bool)>,
    /// Names of firings not yet written into the history.
    names: RowNames,
    /// Every firing named so far, in order.
    changes: Vec<crate::diagnose::onset::NamedChange>,
    /// Told each change as soon as it is named (a live run's status).
    on_named: Option<OnNamed>,
}

/// What is told each change as soon as it is named.
pub type OnNamed = Box<dyn FnMut(&crate::diagnose::onset::NamedChange) + Send>;

impl CalibFiles {
    /// The files written into `dir`: history, trajectory, summary.
    pub fn paths(dir: &Path) -> [PathBuf; 3] {
        [
            dir.join("calibration.csv"),
            dir.join("trajectory.tum"),
            dir.join("summary.json"),
        ]
    }

    /// Starts writing the files of `dir`.
    pub fn create(dir: &Path) -> Result<Self, PipelineError> {
        let [history, trajectory, _] = Self::paths(dir);
        Ok(Self {
            dir: dir.to_path_buf(),
            history: RowFile::create(&history, crate::io::csv::HISTORY_HEADER)?,
            trajectory: TumFile::create(&trajectory)?,
            watch: None,
            held: Default::default(),
            names: RowNames::default(),
            changes: Vec::new(),
            on_named: None,
        })
    }

    /// Tells `f` each change as soon as it is named, during the run.
    pub fn telling(mut self, f: OnNamed) -> Self {
        self.on_named = Some(f);
        self
    }

    /// Names the changes of a filter started from `robot` by `p` (the
    /// history's `change` column, [`Self::changes`]).
    pub fn naming_changes(
        mut self,
        robot: &crate::robot::RobotConfig,
        p: &crate::diagnose::onset::OnsetParams,
    ) -> Self {
        self.watch = Some(super::changes::ChangeWatch::new(robot, p));
        self
    }

    /// Names the firings still pending at the end of the run; returns every
    /// firing named, in order (empty when the detector never fired or
    /// naming is off).
    pub fn changes(&mut self) -> Vec<crate::diagnose::onset::NamedChange> {
        if let Some(w) = self.watch.as_mut() {
            let last = w.finish();
            self.take_names(last);
        }
        self.changes.clone()
    }

    /// Records newly named firings and writes the rows they complete.
    fn take_names(&mut self, named: Vec<crate::diagnose::onset::NamedChange>) {
        for c in named {
            if let Some(f) = self.on_named.as_mut() {
                f(&c);
            }
            self.names.named(&c);
            // A firing on a change already reported is reported once, there.
            let first = c
                .continues
                .and_then(|t| self.changes.iter_mut().rev().find(|p| p.time_s == t));
            match first {
                Some(p) => p.refired_s.push(c.time_s),
                None => self.changes.push(c),
            }
        }
        self.flush(false);
    }

    /// Writes the held rows whose `change` cell is known (all at the end):
    /// a filter firing's name at its own row; a mounting firing's at the
    /// first row at or after its time that carries no filter name.
    fn flush(&mut self, end: bool) {
        let naming = self.watch.is_some();
        let mount_before = self.watch.as_ref().map_or(
            f64::INFINITY,
            super::changes::ChangeWatch::mount_named_before,
        );
        while let Some(&(t, _, fired)) = self.held.front() {
            if !end && t >= mount_before {
                break;
            }
            let Some(name) = self.names.row(t, fired && naming, end) else {
                break;
            };
            let (_, row, _) = self.held.pop_front().expect("front checked");
            self.history
                .row(|w| crate::io::csv::write_history_row(w, &row, &name));
        }
    }

    /// Commits the history and trajectory, then writes `summary.json`.
    pub fn commit(mut self, summary: &impl serde::Serialize) -> Result<(), PipelineError> {
        self.flush(true);
        self.history.commit()?;
        self.trajectory.file.commit()?;
        let [_, _, js] = Self::paths(&self.dir);
        let text = serde_json::to_string_pretty(summary).expect("summary serialises");
        crate::io::atomic::write_bytes_atomic(&js, text.as_bytes())
            .map_err(|e| PipelineError::write(&js, e))
    }
}

impl RunObserver for CalibFiles {
    fn item(&mut self, item: &crate::io::Item) {
        if let Some(w) = self.watch.as_mut() {
            w.item(item);
        }
    }

    fn motion(&mut self, motion: &crate::motion::Motion) {
        if let Some(w) = self.watch.as_mut() {
            w.motion(motion);
        }
    }

    fn step(&mut self, e: &Estimate, _cloud: Option<CloudView<'_>>) {
        self.held.push_back((e.t, e.history_row(), e.changed));
        let named = self.watch.as_mut().map(|w| w.step(e)).unwrap_or_default();
        self.take_names(named);
    }

    fn calibrated_pose(&mut self, t: f64, pose: &Pose2) {
        self.trajectory.pose(t, pose);
    }
}

/// The names of firings not yet written into the history, and the rule
/// that puts them on its rows: a filter firing's at its own row, a
/// laser-mounting firing's at the first row at or after its time that
/// carries no filter name (one name a row).
#[derive(Debug, Default)]
struct RowNames {
    /// Filter firings' names, in firing order.
    filter: std::collections::VecDeque<String>,
    /// Laser-mounting firings' (time (s), name), in time order.
    mount: std::collections::VecDeque<(f64, String)>,
    /// Laser-mounting names whose row is passed, waiting for the next row
    /// without a name of its own.
    carried: std::collections::VecDeque<String>,
}

impl RowNames {
    /// Takes a newly named firing.
    fn named(&mut self, c: &crate::diagnose::onset::NamedChange) {
        if c.detector == crate::diagnose::onset::FILTER {
            self.filter.push_back(c.effect.clone());
        } else {
            let at = self.mount.partition_point(|m| m.0 <= c.time_s);
            self.mount.insert(at, (c.time_s, c.effect.clone()));
        }
    }

    /// The `change` cell of the next row, at `t` (s), where the filter
    /// `fired` or not; `None` while its filter firing is not named yet (at
    /// the `end`, empty). The caller passes a row only once every
    /// mounting firing at or before it is named.
    fn row(&mut self, t: f64, fired: bool, end: bool) -> Option<String> {
        let own = match (fired, self.filter.front()) {
            (false, _) => None,
            (true, Some(_)) => self.filter.pop_front(),
            (true, None) if end => Some(String::new()),
            (true, None) => return None,
        };
        while self.mount.front().is_some_and(|m| m.0 <= t) {
            let (_, m) = self.mount.pop_front().expect("front checked");
            self.carried.push_back(m);
        }
        Some(own.or_else(|| self.carried.pop_front()).unwrap_or_default())
    }
}

/// Motions, their summary and the chained trajectory of one ICP run.
#[derive(Debug, Clone)]
pub struct IcpOutput {
    /// One motion per consecutive scan pair (base frame).
    pub motions: Vec<Motion>,
    /// Counts, iterations and timing.
    pub stats: IcpStats,
    /// Motions chained from the identity at the first scan.
    pub trajectory: Trajectory,
}

impl IcpOutput {
    /// Velocity observations of the valid pairs (failed pairs give none).
    pub fn observations(&self) -> Vec<VelocityObs> {
        self.motions
            .iter()
            .filter_map(VelocityObs::from_motion)
            .collect()
    }
}

/// Keeps a run's results in memory: the motions and ICP trajectory, the
/// estimate after every filter step and the calibrated trajectory.
#[derive(Debug, Default)]
pub struct Collect {
    /// One motion per consecutive scan pair (base frame).
    pub motions: Vec<Motion>,
    /// The motions chained from the identity at the first scan.
    pub icp_trajectory: Trajectory,
    /// The estimate after every filter step.
    pub history: Vec<Estimate>,
    /// The calibrated odometry.
    pub calibrated: Trajectory,
}

impl Collect {
    /// The calibration run these results make with its `summary`.
    pub fn calibration(&mut self, summary: CalibSummary, weight_resets: usize) -> CalibrationRun {
        CalibrationRun {
            summary,
            history: std::mem::take(&mut self.history),
            trajectory: std::mem::take(&mut self.calibrated),
            weight_resets,
        }
    }

    /// The ICP output these results make with its `stats`.
    pub fn icp(&mut self, stats: IcpStats) -> IcpOutput {
        IcpOutput {
            motions: std::mem::take(&mut self.motions),
            stats,
            trajectory: std::mem::take(&mut self.icp_trajectory),
        }
    }
}

impl RunObserver for Collect {
    fn icp_pose(&mut self, t: f64, pose: &Pose2) {
        self.icp_trajectory.push(t, *pose);
    }

    fn motion(&mut self, motion: &Motion) {
        self.motions.push(motion.clone());
    }

    fn step(&mut self, e: &Estimate, _cloud: Option<CloudView<'_>>) {
        self.history.push(*e);
    }

    fn calibrated_pose(&mut self, t: f64, pose: &Pose2) {
        self.calibrated.push(t, *pose);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::onset::{NamedChange, FILTER, MOUNT};

    fn firing(t: f64, detector: &'static str, effect: &str) -> NamedChange {
        NamedChange {
            detector,
            effect: effect.into(),
            ..NamedChange::undetermined(t)
        }
    }

    #[test]
    fn a_mounting_firing_goes_to_the_next_row_without_a_filter_name() {
        let mut n = RowNames::default();
        n.named(&firing(2.0, FILTER, "radius_step"));
        n.named(&firing(1.5, MOUNT, "laser_offset"));
        n.named(&firing(3.2, MOUNT, "laser_offset_2"));
        let rows: Vec<Option<String>> = [(1.0, false), (2.0, true), (3.0, false), (4.0, false)]
            .into_iter()
            .map(|(t, fired)| n.row(t, fired, false))
            .collect();
        let want = ["", "radius_step", "laser_offset", "laser_offset_2"];
        assert_eq!(rows, want.map(|w| Some(w.to_string())));
        // A filter firing not named yet holds its row, unless at the end.
        assert_eq!(n.row(5.0, true, false), None);
        assert_eq!(n.row(5.0, true, true), Some(String::new()));
    }
}
