//! [`Logger`] into a Rerun recording: an `.rrd` file (written beside the
//! target and renamed into place on [`Logger::finish`]), a running viewer, or
//! a freshly spawned one. Temporal data is buffered and sent in columns
//! (`send_columns`), a chunk per few hundred rows, so recording a whole run
//! costs little next to computing it.

use super::clock::ScanClock;
use super::logger::{entity, CalibEstimate, Logger, Stamp, TrajectoryKind};
use super::shapes::{ellipse, growth_steps, thin_prefix};
use super::subsample::systematic_subsample;
use super::trail::{Trail, TrailUpdate};
use super::VizError;
use crate::geom::Pose2;
use nalgebra::Point2;
use rerun::{
    Angle, Arrows2D, Color, LineStrips2D, Points2D, Radius, RecordingStream,
    RecordingStreamBuilder, RotationAxisAngle, Scalars, TimeColumn, Transform3D,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where the recording goes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RerunSink {
    /// An `.rrd` file (the default use).
    File(PathBuf),
    /// A running viewer at `host:port` or a full `rerun+http://…/proxy` URL.
    Connect(String),
    /// Spawn the `rerun` viewer binary found on `PATH` and stream to it.
    Spawn,
}

/// Settings of the Rerun recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RerunOptions {
    /// Application id shown in the viewer.
    pub app_id: String,
    /// Most particles drawn per filter step (systematic subsample by weight).
    pub max_particles: usize,
    /// Rows buffered per entity before a chunk is sent.
    pub batch_rows: usize,
    /// Magnification of the scan-matching 1σ ellipses (they are millimetres).
    pub ellipse_scale: f64,
    /// Most times at which a trajectory is logged as grown so far.
    pub growth_steps: usize,
    /// Most poses in each grown line (every k-th, and the last).
    pub growth_points: usize,
    /// Most scan-matching ellipses in the trail (then every k-th match's).
    pub max_trail: usize,
    /// Most scans remembered to place the grown lines on the `scan`
    /// timeline (then every k-th: a line may show up to k − 1 scans early).
    pub max_clock: usize,
}

impl Default for RerunOptions {
    fn default() -> Self {
        RerunOptions {
            app_id: "odocal".into(),
            max_particles: 256,
            batch_rows: 512,
            ellipse_scale: 100.0,
            growth_steps: 300,
            growth_points: 1000,
            max_trail: 4096,
            max_clock: 1 << 17,
        }
    }
}

/// Points of [`ellipse`]'s outlines.
const ELLIPSE_POINTS: usize = 32;

/// Rows of the robot's pose transform waiting to be sent.
#[derive(Default)]
struct TransformRows {
    scans: Vec<i64>,
    times: Vec<f64>,
    translations: Vec<[f32; 3]>,
    yaws: Vec<f32>,
}

/// Rows of line strips (one strip a row) waiting to be sent.
#[derive(Default)]
struct StripRows {
    scans: Vec<i64>,
    times: Vec<f64>,
    strips: Vec<Vec<[f32; 2]>>,
}

/// Rows of a line-strips entity with any number of strips a row.
#[derive(Default)]
struct MultiStripRows {
    scans: Vec<i64>,
    times: Vec<f64>,
    lengths: Vec<usize>,
    strips: Vec<Vec<[f32; 2]>>,
}

/// Rows of a points entity waiting to be sent as one chunk.
#[derive(Default)]
struct PointRows {
    scans: Vec<i64>,
    times: Vec<f64>,
    lengths: Vec<usize>,
    positions: Vec<[f32; 2]>,
    colors: Vec<Color>,
    radii: Vec<Radius>,
}

/// Rows of a scalar entity waiting to be sent.
#[derive(Default)]
struct ScalarRows {
    scans: Vec<i64>,
    times: Vec<f64>,
    values: Vec<f64>,
}

/// A [`Logger`] writing a Rerun recording (design.md's entities and
/// timelines).
pub struct RerunLogger {
    rec: Option<RecordingStream>,
    options: RerunOptions,
    /// `(temporary, final)` paths of a file sink.
    file: Option<(PathBuf, PathBuf)>,
    scans: PointRows,
    particles: PointRows,
    scalars: BTreeMap<&'static str, ScalarRows>,
    robot: TransformRows,
    ellipses: StripRows,
    /// Every match's ellipse (world frame) up to the cursor.
    trail: Trail<Vec<[f32; 2]>>,
    /// Rows of the trail's levels waiting to be sent.
    trail_rows: BTreeMap<usize, MultiStripRows>,
    /// Scans logged, to place the grown lines on the `scan` timeline.
    clock: ScanClock,
    /// The laser mounting last logged (static).
    mount: Option<Pose2>,
}

pub(super) fn rerun_err(e: impl std::fmt::Display) -> VizError {
    VizError::Rerun(e.to_string())
}

/// Sends what `rec` holds and closes it; a file sink's temporary file
/// `(temporary, final)` is then synced and renamed into place.
pub(super) fn close(
    rec: RecordingStream,
    file: Option<(PathBuf, PathBuf)>,
) -> Result<(), VizError> {
    rec.flush_blocking().map_err(rerun_err)?;
    // Dropping the last handle closes the sink; a file sink writes its
    // footer and joins its writer thread.
    drop(rec);
    if let Some((tmp, path)) = file {
        let f = std::fs::File::open(&tmp).map_err(|e| VizError::io(&tmp, e))?;
        f.sync_all().map_err(|e| VizError::io(&tmp, e))?;
        std::fs::rename(&tmp, &path).map_err(|e| VizError::io(&path, e))?;
    }
    Ok(())
}

/// Beside `path`, the temporary file a recording is written to until it is
/// complete.
pub(super) fn temp_rrd(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "recording.rrd".into());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

fn viewer_on_path() -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join("rerun").is_file()))
}

/// Viridis-like colour for a relative weight in [0, 1].
fn weight_color(rel: f64) -> Color {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = rel.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let c: Vec<u8> = (0..3)
        .map(|k| (STOPS[i][k] + f * (STOPS[i + 1][k] - STOPS[i][k])).round() as u8)
        .collect();
    Color::from_rgb(c[0], c[1], c[2])
}

fn rgb(c: [u8; 3]) -> Color {
    Color::from_rgb(c[0], c[1], c[2])
}

/// A planar pose as a transform about the z axis.
fn planar_transform(p: &Pose2) -> Transform3D {
    let t = p.translation.vector;
    Transform3D::from_translation_rotation(
        [t.x as f32, t.y as f32, 0.0],
        RotationAxisAngle::new(
            [0.0, 0.0, 1.0],
            Angle::from_radians(p.rotation.angle() as f32),
        ),
    )
}

impl RerunLogger {
    /// Opens a recording to `sink`. A file sink writes to a temporary file
    /// beside the target until [`Logger::finish`]; `Spawn` fails clearly when
    /// no `rerun` binary is on `PATH`.
    pub fn new(sink: RerunSink, options: RerunOptions) -> Result<Self, VizError> {
        if [
            options.max_particles,
            options.batch_rows,
            options.growth_steps,
            options.max_trail,
            options.max_clock,
        ]
        .contains(&0)
        {
            return Err(VizError::Input(
                "max_particles, batch_rows, growth_steps, max_trail and max_clock must be \
                 positive"
                    .into(),
            ));
        }
        if !(options.ellipse_scale.is_finite() && options.ellipse_scale > 0.0) {
            return Err(VizError::Input("ellipse_scale must be positive".into()));
        }
        let app = rerun::ApplicationId::try_new(options.app_id.clone())
            .map_err(|e| VizError::Input(format!("app_id: {e}")))?;
        let builder = RecordingStreamBuilder::new(app)
            .with_blueprint(super::rerun_layout::blueprint(options.ellipse_scale));
        let (rec, file) = match sink {
            RerunSink::File(path) => {
                if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| VizError::io(dir, e))?;
                }
                let tmp = temp_rrd(&path);
                (builder.save(&tmp).map_err(rerun_err)?, Some((tmp, path)))
            }
            RerunSink::Connect(addr) => {
                let url = if addr.contains("://") {
                    addr
                } else {
                    format!("rerun+http://{addr}/proxy")
                };
                (builder.connect_grpc_opts(url).map_err(rerun_err)?, None)
            }
            RerunSink::Spawn => {
                if !viewer_on_path() {
                    return Err(VizError::Rerun(
                        "no `rerun` viewer binary on PATH (install rerun-sdk==0.36.3)".into(),
                    ));
                }
                (builder.spawn().map_err(rerun_err)?, None)
            }
        };
        let logger = RerunLogger {
            rec: Some(rec),
            trail: Trail::new(options.max_trail),
            trail_rows: BTreeMap::new(),
            clock: ScanClock::new(options.max_clock),
            options,
            file,
            scans: PointRows::default(),
            particles: PointRows::default(),
            scalars: BTreeMap::new(),
            robot: TransformRows::default(),
            ellipses: StripRows::default(),
            mount: None,
        };
        let heading = Arrows2D::from_vectors([[0.3f32, 0.0]])
            .with_colors([Color::from_rgb(230, 120, 0)])
            .with_radii([Radius::new_ui_points(2.0)]);
        logger
            .rec()?
            .log_static(entity::ROBOT_HEADING, &heading)
            .map_err(rerun_err)?;
        logger.style_ellipses()?;
        Ok(logger)
    }

    /// Records to the `.rrd` file `path` with default options.
    pub fn to_file(path: impl Into<PathBuf>) -> Result<Self, VizError> {
        Self::new(RerunSink::File(path.into()), RerunOptions::default())
    }

    fn rec(&self) -> Result<&RecordingStream, VizError> {
        self.rec
            .as_ref()
            .ok_or_else(|| VizError::Rerun("recording already finished".into()))
    }

    fn push_scalar(&mut self, path: &'static str, at: Stamp, value: f64) -> Result<(), VizError> {
        if !value.is_finite() {
            return Err(VizError::Input(format!(
                "{path}: non-finite value at scan {}",
                at.scan
            )));
        }
        let rows = self.scalars.entry(path).or_default();
        rows.scans.push(at.scan);
        rows.times.push(at.time);
        rows.values.push(value);
        if rows.values.len() >= self.options.batch_rows * 8 {
            self.flush_scalar(path)?;
        }
        Ok(())
    }

    fn flush_scalar(&mut self, path: &'static str) -> Result<(), VizError> {
        let Some(rows) = self.scalars.get_mut(path) else {
            return Ok(());
        };
        if rows.values.is_empty() {
            return Ok(());
        }
        let rows = std::mem::take(rows);
        let columns = Scalars::new(rows.values)
            .columns_of_unit_batches()
            .map_err(rerun_err)?;
        self.send_rows(path, rows.scans, rows.times, columns)
    }

    fn flush_points(&mut self, which: &'static str) -> Result<(), VizError> {
        let rows = match which {
            entity::SCAN_POINTS => std::mem::take(&mut self.scans),
            _ => std::mem::take(&mut self.particles),
        };
        if rows.lengths.is_empty() {
            return Ok(());
        }
        let mut points = Points2D::new(rows.positions);
        if !rows.colors.is_empty() {
            points = points.with_colors(rows.colors);
        }
        if !rows.radii.is_empty() {
            points = points.with_radii(rows.radii);
        }
        let columns = points.columns(rows.lengths).map_err(rerun_err)?;
        self.send_rows(which, rows.scans, rows.times, columns)
    }

    fn flush_robot(&mut self) -> Result<(), VizError> {
        let rows = std::mem::take(&mut self.robot);
        if rows.yaws.is_empty() {
            return Ok(());
        }
        let rotations = rows
            .yaws
            .iter()
            .map(|&y| RotationAxisAngle::new([0.0, 0.0, 1.0], Angle::from_radians(y)));
        let columns = Transform3D::update_fields()
            .with_many_translation(rows.translations)
            .with_many_rotation_axis_angle(rotations)
            .columns_of_unit_batches()
            .map_err(rerun_err)?;
        self.send_rows(entity::ROBOT, rows.scans, rows.times, columns)
    }

    /// Sends `columns`, one row per scan index and time.
    fn send_rows(
        &self,
        path: &str,
        scans: Vec<i64>,
        times: Vec<f64>,
        columns: impl IntoIterator<Item = rerun::SerializedComponentColumn>,
    ) -> Result<(), VizError> {
        self.rec()?
            .send_columns(
                path,
                [
                    TimeColumn::new_sequence(entity::SCAN, scans),
                    TimeColumn::new_duration_secs(entity::TIME, times),
                ],
                columns,
            )
            .map_err(rerun_err)
    }

    fn flush_ellipses(&mut self) -> Result<(), VizError> {
        let rows = std::mem::take(&mut self.ellipses);
        if rows.strips.is_empty() {
            return Ok(());
        }
        let columns = LineStrips2D::new(rows.strips)
            .columns_of_unit_batches()
            .map_err(rerun_err)?;
        self.send_rows(entity::ICP_COVARIANCE, rows.scans, rows.times, columns)
    }

    /// The colour of the latest ellipse (bright), static, so that the rows
    /// carry the outlines only.
    fn style_ellipses(&self) -> Result<(), VizError> {
        let latest = LineStrips2D::update_fields()
            .with_colors([Color::from_rgb(230, 120, 0)])
            .with_radii([Radius::new_ui_points(1.5)]);
        self.rec()?
            .log_static(entity::ICP_COVARIANCE, &latest)
            .map_err(rerun_err)
    }

    /// Queues the trail's changed levels as rows at `at`; a level used for
    /// the first time gets its faint colour (static).
    fn push_trail(
        &mut self,
        at: Stamp,
        updates: Vec<TrailUpdate<Vec<[f32; 2]>>>,
    ) -> Result<(), VizError> {
        for u in updates {
            if !self.trail_rows.contains_key(&u.level) {
                let faint = LineStrips2D::update_fields()
                    .with_colors([Color::from_unmultiplied_rgba(31, 119, 180, 110)])
                    .with_radii([Radius::new_ui_points(0.75)]);
                self.rec()?
                    .log_static(entity::trail_level(u.level), &faint)
                    .map_err(rerun_err)?;
            }
            let rows = self.trail_rows.entry(u.level).or_default();
            rows.scans.push(at.scan);
            rows.times.push(at.time);
            rows.lengths.push(u.items.len());
            rows.strips.extend(u.items);
            if rows.lengths.len() >= self.options.batch_rows {
                self.flush_trail(u.level)?;
            }
        }
        Ok(())
    }

    fn flush_trail(&mut self, level: usize) -> Result<(), VizError> {
        let Some(rows) = self.trail_rows.get_mut(&level) else {
            return Ok(());
        };
        if rows.lengths.is_empty() {
            return Ok(());
        }
        let rows = std::mem::take(rows);
        let columns = LineStrips2D::new(rows.strips)
            .columns(rows.lengths)
            .map_err(rerun_err)?;
        self.send_rows(&entity::trail_level(level), rows.scans, rows.times, columns)
    }

    /// The trajectory up to each of [`growth_steps`]'s poses, on `time`, and
    /// on `scan` at the last scan logged at or before each (when any was).
    fn log_growth(
        &mut self,
        kind: TrajectoryKind,
        times: &[f64],
        strip: &[[f32; 2]],
    ) -> Result<(), VizError> {
        let steps = growth_steps(strip.len(), self.options.growth_steps);
        let strips: Vec<Vec<[f32; 2]>> = steps
            .iter()
            .map(|&i| {
                thin_prefix(i, self.options.growth_points)
                    .into_iter()
                    .map(|k| strip[k])
                    .collect()
            })
            .collect();
        let t: Vec<f64> = steps.iter().map(|&i| times[i]).collect();
        let mut timelines = vec![];
        if !self.clock.is_empty() {
            let scans: Vec<i64> = t.iter().filter_map(|&x| self.clock.scan_at(x)).collect();
            timelines.push(TimeColumn::new_sequence(entity::SCAN, scans));
        }
        timelines.push(TimeColumn::new_duration_secs(entity::TIME, t));
        let n = strips.len();
        let mut columns: Vec<_> = LineStrips2D::new(strips)
            .columns_of_unit_batches()
            .map_err(rerun_err)?
            .collect();
        // Colour and width once per row, as the rows of the strip column.
        columns.extend(
            LineStrips2D::update_fields()
                .with_colors(vec![rgb(kind.color()); n])
                .with_radii(vec![Radius::new_ui_points(1.5); n])
                .columns_of_unit_batches()
                .map_err(rerun_err)?,
        );
        self.rec()?
            .send_columns(kind.entity(), timelines, columns)
            .map_err(rerun_err)
    }

    fn flush_all(&mut self) -> Result<(), VizError> {
        self.flush_robot()?;
        self.flush_ellipses()?;
        let levels: Vec<usize> = self.trail_rows.keys().copied().collect();
        for level in levels {
            self.flush_trail(level)?;
        }
        self.flush_points(entity::SCAN_POINTS)?;
        self.flush_points(entity::PARTICLES)?;
        let keys: Vec<&'static str> = self.scalars.keys().copied().collect();
        for k in keys {
            self.flush_scalar(k)?;
        }
        Ok(())
    }
}

impl Logger for RerunLogger {
    fn map(&mut self, segments: &[[Point2<f64>; 2]]) -> Result<(), VizError> {
        let strips = segments
            .iter()
            .map(|[a, b]| [[a.x as f32, a.y as f32], [b.x as f32, b.y as f32]]);
        let strips = LineStrips2D::new(strips)
            .with_colors([Color::from_rgb(120, 120, 120)])
            .with_radii([Radius::new_ui_points(1.0)]);
        self.rec()?
            .log_static(entity::MAP, &strips)
            .map_err(rerun_err)
    }

    fn scan(
        &mut self,
        at: Stamp,
        world_from_base: &Pose2,
        base_from_sensor: &Pose2,
        points: &[Point2<f64>],
    ) -> Result<(), VizError> {
        at.check()?;
        self.rec()?;
        if self.mount != Some(*base_from_sensor) {
            self.mount = Some(*base_from_sensor);
            self.rec()?
                .log_static(entity::LASER, &planar_transform(base_from_sensor))
                .map_err(rerun_err)?;
        }
        self.clock.note(at.time, at.scan);
        let robot = &mut self.robot;
        robot.scans.push(at.scan);
        robot.times.push(at.time);
        let t = world_from_base.translation.vector;
        robot.translations.push([t.x as f32, t.y as f32, 0.0]);
        robot.yaws.push(world_from_base.rotation.angle() as f32);
        let rows = &mut self.scans;
        rows.scans.push(at.scan);
        rows.times.push(at.time);
        rows.lengths.push(points.len());
        rows.positions
            .extend(points.iter().map(|p| [p.x as f32, p.y as f32]));
        if rows.lengths.len() >= self.options.batch_rows {
            self.flush_robot()?;
            self.flush_points(entity::SCAN_POINTS)?;
        }
        Ok(())
    }

    fn trajectory(
        &mut self,
        kind: TrajectoryKind,
        times: &[f64],
        poses: &[Pose2],
    ) -> Result<(), VizError> {
        if times.len() != poses.len() {
            return Err(VizError::Input(format!(
                "{}: {} times for {} poses",
                kind.entity(),
                times.len(),
                poses.len()
            )));
        }
        if let Some(t) = times.iter().find(|t| !t.is_finite()) {
            return Err(VizError::Input(format!("{}: time {t}", kind.entity())));
        }
        let strip: Vec<[f32; 2]> = poses
            .iter()
            .map(|p| [p.translation.x as f32, p.translation.y as f32])
            .collect();
        let [r, g, b] = kind.color();
        let full = LineStrips2D::new([strip.clone()])
            .with_colors([Color::from_unmultiplied_rgba(r, g, b, 70)])
            .with_radii([Radius::new_ui_points(1.0)]);
        self.rec()?
            .log_static(kind.full_entity(), &full)
            .map_err(rerun_err)?;
        self.log_growth(kind, times, &strip)
    }

    fn icp_covariance(
        &mut self,
        at: Stamp,
        world_from_base: &Pose2,
        cov_xy: [[f64; 2]; 2],
    ) -> Result<(), VizError> {
        at.check()?;
        self.rec()?;
        let outline = ellipse(
            world_from_base,
            cov_xy,
            1.0,
            self.options.ellipse_scale,
            ELLIPSE_POINTS,
        )
        .ok_or_else(|| {
            VizError::Input(format!(
                "{}: covariance {cov_xy:?} at scan {} is not positive semidefinite",
                entity::ICP_COVARIANCE,
                at.scan
            ))
        })?;
        let strip: Vec<[f32; 2]> = outline.iter().map(|p| [p[0] as f32, p[1] as f32]).collect();
        let updates = self.trail.push(strip.clone());
        self.push_trail(at, updates)?;
        let rows = &mut self.ellipses;
        rows.scans.push(at.scan);
        rows.times.push(at.time);
        rows.strips.push(strip);
        if rows.strips.len() >= self.options.batch_rows {
            self.flush_ellipses()?;
        }
        Ok(())
    }

    fn particles(
        &mut self,
        at: Stamp,
        r_right: &[f64],
        r_left: &[f64],
        weights: &[f64],
    ) -> Result<(), VizError> {
        at.check()?;
        if r_right.len() != r_left.len() || r_right.len() != weights.len() {
            return Err(VizError::Input(format!(
                "particles: {} R_R, {} R_L, {} weights",
                r_right.len(),
                r_left.len(),
                weights.len()
            )));
        }
        self.rec()?;
        let shown = systematic_subsample(weights, self.options.max_particles);
        let w = |i: usize| {
            let x = weights[i];
            if x.is_finite() && x > 0.0 {
                x
            } else {
                0.0
            }
        };
        let wmax = shown.iter().map(|&i| w(i)).fold(0.0, f64::max);
        let rows = &mut self.particles;
        rows.scans.push(at.scan);
        rows.times.push(at.time);
        rows.lengths.push(shown.len());
        for &i in &shown {
            let rel = if wmax > 0.0 { w(i) / wmax } else { 1.0 };
            rows.positions.push([r_right[i] as f32, r_left[i] as f32]);
            rows.colors.push(weight_color(rel));
            rows.radii
                .push(Radius::new_ui_points((1.5 + 3.5 * rel) as f32));
        }
        if rows.lengths.len() >= self.options.batch_rows {
            self.flush_points(entity::PARTICLES)?;
        }
        self.push_scalar(entity::PARTICLES_SHOWN, at, shown.len() as f64)
    }

    fn estimate(&mut self, at: Stamp, e: &CalibEstimate) -> Result<(), VizError> {
        at.check()?;
        self.rec()?;
        let paths = [
            (entity::EST_R_RIGHT, e.params[0]),
            (entity::EST_R_LEFT, e.params[1]),
            (entity::EST_WHEEL_BASE, e.params[2]),
            (entity::STD_R_RIGHT, e.std[0]),
            (entity::STD_R_LEFT, e.std[1]),
            (entity::STD_WHEEL_BASE, e.std[2]),
            (entity::PARTICLES_COUNT, e.particles as f64),
            (entity::PROCESS_SIGMA, e.process_sigma),
        ];
        if let Some((p, _)) = paths.iter().find(|(_, v)| !v.is_finite()) {
            return Err(VizError::Input(format!(
                "{p}: non-finite value at scan {}",
                at.scan
            )));
        }
        for (p, v) in paths {
            self.push_scalar(p, at, v)?;
        }
        Ok(())
    }

    fn change(&mut self, at: Stamp, text: &str) -> Result<(), VizError> {
        at.check()?;
        let log = rerun::TextLog::new(text).with_level(rerun::TextLogLevel::WARN);
        let columns = log.columns_of_unit_batches().map_err(rerun_err)?;
        self.send_rows(entity::CHANGES, vec![at.scan], vec![at.time], columns)
    }

    fn icp(&mut self, at: Stamp, iterations: u32, covariance_trace: f64) -> Result<(), VizError> {
        at.check()?;
        self.rec()?;
        if !covariance_trace.is_finite() {
            return Err(VizError::Input(format!(
                "{}: non-finite value at scan {}",
                entity::ICP_COV_TRACE,
                at.scan
            )));
        }
        self.push_scalar(entity::ICP_ITERATIONS, at, iterations as f64)?;
        self.push_scalar(entity::ICP_COV_TRACE, at, covariance_trace)
    }

    fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if self.trail.stride() > 1 {
            notes.push(format!(
                "the scan-matching ellipse trail shows one match in {} ({} matches, at most {} \
                 ellipses)",
                self.trail.stride(),
                self.trail.seen(),
                self.options.max_trail
            ));
        }
        if self.clock.stride() > 1 {
            notes.push(format!(
                "on the scan timeline the grown trajectories are placed to within {} scans \
                 (at most {} scans remembered)",
                self.clock.stride(),
                self.options.max_clock
            ));
        }
        notes
    }

    fn finish(&mut self) -> Result<(), VizError> {
        if self.rec.is_none() {
            return Ok(());
        }
        self.flush_all()?;
        let rec = self.rec.take().expect("checked above");
        close(rec, self.file.take())
    }
}

impl Drop for RerunLogger {
    fn drop(&mut self) {
        // Dropped without `finish` (an error path): like every odocal write,
        // leave the previous file or none, never a partial one.
        drop(self.rec.take());
        if let Some((tmp, _)) = self.file.take() {
            let _ = std::fs::remove_file(tmp);
        }
    }
}
