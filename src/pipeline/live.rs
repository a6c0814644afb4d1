//! `odocal live`: `odocal calibrate`'s calibration as a ROS 2 node. The
//! robot's topics come off the DDS domain ([`crate::live::ros2`]), go
//! through the same driver as a recording (ICP, the online front end and
//! filters, change naming), and the node publishes the wheel odometry
//! integrated with the current estimate at the wheels' rate, a diagnostic
//! status at least once a second, and the multipliers as parameters. When
//! stopped (SIGINT, SIGTERM) it writes `calibrate`'s outputs, and
//! `live.json`: what the run measured of itself (latencies, CPU, traffic).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde::Serialize;

use super::calibrate::{self, CalibSource, CalibrateJob, CalibrateOutcome, CalibratorChoice};
use super::observe::RunObserver;
use super::{Common, PipelineError, Viewer};
use crate::calib::{CloudView, Estimate};
use crate::geom::{self, Pose2};
use crate::io::{Item, ReadOptions};
use crate::live::ros2::msgs;
use crate::live::ros2::{Listener, Ros2Node, PARAMETERS};
use crate::live::source::{Log, SharedTraffic};
use crate::live::{Inlet, InletStats, LiveParams, LiveSource, StatusBoard};
use crate::recording::WheelSample;

/// The topic the calibrated odometry is published on.
pub const ODOMETRY_TOPIC: &str = "/odocal/odometry";
/// The topic of the diagnostics.
pub const DIAGNOSTICS_TOPIC: &str = "/diagnostics";
/// The name of the node's diagnostic status.
pub const STATUS_NAME: &str = "odocal: calibration";

/// What `odocal live` is asked to do.
#[derive(Debug, Clone)]
pub struct LiveJob {
    /// Where `calibrate`'s outputs and `live.json` go when stopped.
    pub out: PathBuf,
    /// Overrides of the configured calibrator.
    pub choice: CalibratorChoice,
    /// Where to show the run in the Rerun viewer.
    pub viewer: Option<Viewer>,
    /// Configuration and robot files.
    pub common: Common,
    /// The node's name.
    pub node: String,
}

/// Percentiles of a latency (ms).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Latency {
    /// Samples.
    pub n: usize,
    /// Median (ms).
    pub median_ms: f64,
    /// 95th percentile (ms).
    pub p95_ms: f64,
    /// Largest (ms).
    pub max_ms: f64,
}

impl Latency {
    fn of(mut v: Vec<f64>) -> Self {
        if v.is_empty() {
            return Self::default();
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
        Self {
            n: v.len(),
            median_ms: q(0.5),
            p95_ms: q(0.95),
            max_ms: v[v.len() - 1],
        }
    }
}

/// What a live run measured of itself (`DIR/live.json`).
#[derive(Debug, Clone, Serialize)]
pub struct LiveReport {
    /// The DDS domain.
    pub domain: u16,
    /// Whether only 127.0.0.1 was used.
    pub localhost_only: bool,
    /// From joining the domain to the first scan and wheel samples (s):
    /// discovery and the publishers' first messages.
    pub start_s: f64,
    /// From joining to the end (s).
    pub run_s: f64,
    /// Process CPU time over the run (s; user + system, all threads).
    pub cpu_s: f64,
    /// CPU time over wall time (1.0 is one core busy).
    pub cpu_share: f64,
    /// From a scan's arrival to the filter step that ends at it, for scans
    /// that arrived once the filters ran.
    pub scan_to_estimate: Latency,
    /// From a wheel message's arrival to its odometry published.
    pub wheel_to_odometry: Latency,
    /// Odometry messages published.
    pub odometry_published: u64,
    /// Diagnostic arrays published.
    pub diagnostics_published: u64,
    /// Messages received, refused, dropped on a full queue, too large.
    pub messages: [u64; 4],
    /// Samples handed to the calibration: scans, wheels, gyro, odometry.
    pub samples: [u64; 4],
    /// Scans dropped while the wheels were silent.
    pub scans_dropped: u64,
}

/// Process CPU time (s) so far, user + system (from `/proc/self/stat`;
/// `None` where there is none).
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let after = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    // USER_HZ is 100 on every Linux this runs on.
    Some(ticks / 100.0)
}

/// The topics a live run subscribes to, each once, with its ROS type: the
/// scans, the wheels' source, the gyro, the robot's odometry (when it is
/// not the wheels' topic already) and the transforms.
pub fn topics(read: &ReadOptions) -> Vec<(String, String)> {
    use crate::io::ros_msgs::{ImuMsg, LaserScanMsg, OdometryMsg, RosMsg, TfMessage};
    let t = &read.topics;
    let mut out: Vec<(String, String)> = Vec::new();
    for (topic, ty) in [
        (t.scan.as_str(), LaserScanMsg::TYPE),
        (read.wheel_topic(), read.wheel_type()),
        (t.imu.as_str(), ImuMsg::TYPE),
        (t.odom.as_str(), OdometryMsg::TYPE),
        (t.tf_static.as_str(), TfMessage::TYPE),
        (t.tf.as_str(), TfMessage::TYPE),
    ] {
        if !out.iter().any(|(o, _)| o == topic) {
            out.push((topic.to_string(), ty.to_string()));
        }
    }
    out
}

/// Sees the run: publishes the odometry at each wheel sample, keeps the
/// status board and measures the latencies.
struct LiveObserver {
    odometry: ros2_client::Publisher<msgs::Odometry>,
    board: Arc<Mutex<StatusBoard>>,
    traffic: SharedTraffic,
    frames: (String, String),
    last: Option<WheelSample>,
    pose: Pose2,
    scan_latency_ms: Vec<f64>,
    wheel_latency_ms: Vec<f64>,
    /// When the first filter step came.
    first_step: Option<Instant>,
}

/// Latency samples kept (the first ones; enough for percentiles, bounded).
const LATENCY_SAMPLES: usize = 100_000;

impl LiveObserver {
    fn new(
        odometry: ros2_client::Publisher<msgs::Odometry>,
        (board, traffic): (Arc<Mutex<StatusBoard>>, SharedTraffic),
        frames: (String, String),
    ) -> Self {
        Self {
            odometry,
            board,
            traffic,
            frames,
            last: None,
            pose: Pose2::identity(),
            scan_latency_ms: Vec::new(),
            wheel_latency_ms: Vec::new(),
            first_step: None,
        }
    }

    fn wheel(&mut self, w: &WheelSample) {
        let drive = self.board.lock().ok().and_then(|b| b.drive());
        let (Some(prev), Some(drive)) = (self.last, drive) else {
            self.last = Some(*w);
            return;
        };
        self.last = Some(*w);
        let inc = drive.increment(w.right - prev.right, w.left - prev.left);
        self.pose *= inc;
        let dt = w.stamp - prev.stamp;
        let (v, wz) = if dt > 0.0 {
            (inc.translation.vector.x / dt, geom::heading(&inc) / dt)
        } else {
            (0.0, 0.0)
        };
        let m = odometry_msg(w.stamp, &self.pose, (v, wz), &self.frames);
        if self.odometry.publish(m).is_ok() {
            if let Ok(mut b) = self.board.lock() {
                b.odometry += 1;
            }
            let arrived = self.traffic.lock().ok().and_then(|t| t.wheel_arrival);
            if let (Some(a), true) = (arrived, self.wheel_latency_ms.len() < LATENCY_SAMPLES) {
                self.wheel_latency_ms.push(a.elapsed().as_secs_f64() * 1e3);
            }
        }
    }
}

/// `nav_msgs/Odometry` of `pose` at `stamp` (s) with the body velocity
/// `(v (m/s), w (rad/s))`, in `frames` (parent, child); covariances zero:
/// not estimated.
fn odometry_msg(
    stamp: f64,
    pose: &Pose2,
    (v, w): (f64, f64),
    frames: &(String, String),
) -> msgs::Odometry {
    let [x, y, th] = geom::xyt(pose);
    let vector = |x, z| msgs::Vector3 { x, y: 0.0, z };
    msgs::Odometry {
        header: msgs::Header {
            stamp: msgs::Time::from_seconds(stamp),
            frame_id: frames.0.clone(),
        },
        child_frame_id: frames.1.clone(),
        pose: msgs::PoseWithCovariance {
            pose: msgs::Pose {
                position: msgs::Vector3 { x, y, z: 0.0 },
                orientation: msgs::Quaternion::from_yaw(th),
            },
            covariance: msgs::Covariance([0.0; 36]),
        },
        twist: msgs::TwistWithCovariance {
            twist: msgs::Twist {
                linear: vector(v, 0.0),
                angular: vector(0.0, w),
            },
            covariance: msgs::Covariance([0.0; 36]),
        },
    }
}

impl RunObserver for LiveObserver {
    fn item(&mut self, item: &Item) {
        if let Item::Wheel(w) = item {
            self.wheel(w);
        }
    }

    fn step(&mut self, estimate: &Estimate, _cloud: Option<CloudView<'_>>) {
        if let Ok(mut b) = self.board.lock() {
            b.step(estimate);
        }
        // Once the filters run: the steps of the warm-up's backlog, made at
        // once when they start, say how long the warm-up was, not how fast
        // the node follows the robot.
        let started = *self.first_step.get_or_insert_with(Instant::now);
        let arrived = self
            .traffic
            .lock()
            .ok()
            .and_then(|t| t.scan_arrival(estimate.t))
            .filter(|a| *a > started);
        if let (Some(a), true) = (arrived, self.scan_latency_ms.len() < LATENCY_SAMPLES) {
            self.scan_latency_ms.push(a.elapsed().as_secs_f64() * 1e3);
        }
    }

    fn front(&mut self, _t: f64, time_offset_s: f64, laser: [f64; 3]) {
        if let Ok(mut b) = self.board.lock() {
            b.time_offset_s = time_offset_s;
            b.laser = laser;
        }
    }
}

/// The diagnostics thread's state: publishes the board's status at the
/// configured rate and keeps the parameters at the board's multipliers.
struct Reporter {
    node: Arc<Ros2Node>,
    publisher: ros2_client::Publisher<msgs::DiagnosticArray>,
    board: Arc<Mutex<StatusBoard>>,
    traffic: SharedTraffic,
    stats: Arc<InletStats>,
    params: LiveParams,
    hardware: String,
    published: u64,
    log: Arc<Mutex<Log>>,
    last_level: Option<crate::live::Level>,
}

impl Reporter {
    fn report(&mut self) {
        let now = Instant::now();
        let (status, multipliers, t) = {
            let (Ok(b), Ok(traffic)) = (self.board.lock(), self.traffic.lock()) else {
                return;
            };
            let s = b.status(&traffic, self.stats.counts(), &self.params, now);
            (s, b.multipliers(), b.estimate.as_ref().map(|e| e.t))
        };
        if self.last_level != Some(status.level) {
            if let Ok(mut log) = self.log.lock() {
                log(&format!("status {:?}: {}", status.level, status.message));
            }
            self.last_level = Some(status.level);
        }
        let stamp = t.unwrap_or_else(wall_seconds);
        let m = msgs::DiagnosticArray {
            header: msgs::Header {
                stamp: msgs::Time::from_seconds(stamp),
                frame_id: String::new(),
            },
            status: vec![msgs::DiagnosticStatus {
                level: status.level as u8,
                name: STATUS_NAME.into(),
                message: status.message,
                hardware_id: self.hardware.clone(),
                values: status
                    .values
                    .into_iter()
                    .map(|(key, value)| msgs::KeyValue { key, value })
                    .collect(),
            }],
        };
        if self.publisher.publish(m).is_ok() {
            self.published += 1;
        }
        if let Some(m) = multipliers {
            for (name, v) in PARAMETERS.iter().zip(m) {
                let _ = self.node.set_parameter(name, v);
            }
        }
    }

    /// Reports until `done`, then once more.
    fn run(mut self, done: Arc<AtomicBool>) -> u64 {
        let period = Duration::from_secs_f64(1.0 / self.params.diagnostics_hz);
        let mut next = Instant::now();
        while !done.load(Ordering::Relaxed) {
            if Instant::now() >= next {
                self.report();
                next += period;
            }
            std::thread::sleep(Duration::from_millis(20).min(period));
        }
        self.report();
        self.published
    }
}

/// Seconds since the epoch now.
fn wall_seconds() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// What `odocal live` gives: the calibration (as `calibrate`) and what the
/// run measured of itself.
pub struct LiveOutcome {
    /// The calibration.
    pub calibration: CalibrateOutcome,
    /// `live.json`.
    pub report: LiveReport,
}

/// Where a live run joins: the domain and whether on 127.0.0.1 only, from
/// the configuration, else the ROS 2 environment variables.
pub fn network(live: &LiveParams) -> Result<(u16, bool), PipelineError> {
    let env = |k: &str| std::env::var(k).ok();
    let domain = live
        .domain(env("ROS_DOMAIN_ID").as_deref())
        .map_err(PipelineError::BadArgument)?;
    let localhost = live.localhost(
        env("ROS_LOCALHOST_ONLY").as_deref(),
        env("ROS_AUTOMATIC_DISCOVERY_RANGE").as_deref(),
    );
    Ok((domain, localhost))
}

fn net(e: crate::live::ros2::Ros2Error) -> PipelineError {
    PipelineError::Network(e.to_string())
}

/// The node joined, its publishers, and the listener feeding the inlet.
struct Joined {
    node: Ros2Node,
    odometry: ros2_client::Publisher<msgs::Odometry>,
    diagnostics: ros2_client::Publisher<msgs::DiagnosticArray>,
    listener: Listener,
    rx: std::sync::mpsc::Receiver<crate::live::Incoming>,
    stats: Arc<InletStats>,
    subscribed: Vec<(String, String)>,
    _spinner: std::thread::JoinHandle<()>,
}

/// Joins `domain` as the job's node, makes the publishers and starts
/// listening to the topics `read` names.
fn join(
    job: &LiveJob,
    live: &LiveParams,
    read: &ReadOptions,
    (domain, localhost): (u16, bool),
    stop: &Arc<AtomicBool>,
) -> Result<Joined, PipelineError> {
    let mut node = Ros2Node::join(&job.node, domain, localhost, true).map_err(net)?;
    let spinner = node.spin().map_err(net)?;
    let odometry = node
        .publisher::<msgs::Odometry>(ODOMETRY_TOPIC, ("nav_msgs", "Odometry"), 50)
        .map_err(net)?;
    let diagnostics = node
        .publisher::<msgs::DiagnosticArray>(
            DIAGNOSTICS_TOPIC,
            ("diagnostic_msgs", "DiagnosticArray"),
            10,
        )
        .map_err(net)?;
    let subscribed = topics(read);
    let (inlet, rx, stats) = Inlet::new(live.queue, live.max_message_bytes);
    let latched = std::slice::from_ref(&read.topics.tf_static);
    let listener =
        Listener::start(&node, &subscribed, latched, inlet, stop.clone()).map_err(net)?;
    Ok(Joined {
        node,
        odometry,
        diagnostics,
        listener,
        rx,
        stats,
        subscribed,
        _spinner: spinner,
    })
}

/// A log shared by the threads of a run.
type SharedLog = Arc<Mutex<Log>>;

fn say(log: &SharedLog, m: &str) {
    if let Ok(mut l) = log.lock() {
        l(m)
    }
}

/// Starts the diagnostics thread; raise the flag returned to end it (it
/// reports once more and gives how many arrays it published).
fn report_on(
    reporter: Reporter,
) -> Result<(std::thread::JoinHandle<u64>, Arc<AtomicBool>), PipelineError> {
    let done = Arc::new(AtomicBool::new(false));
    let flag = done.clone();
    let handle = std::thread::Builder::new()
        .name("odocal-diagnostics".into())
        .spawn(move || reporter.run(flag))
        .map_err(|e| PipelineError::Network(e.to_string()))?;
    Ok((handle, done))
}

/// `calibrate` over the live source: the status board told each named
/// change, the wheel source described from what came.
fn calibrate_live(
    job: &LiveJob,
    name: &str,
    source: &mut LiveSource<'_>,
    (read, nominal): (&ReadOptions, &super::Nominal),
    (board, log): (&Arc<Mutex<StatusBoard>>, &SharedLog),
    observer: &mut LiveObserver,
) -> Result<CalibrateOutcome, PipelineError> {
    let cal_job = CalibrateJob {
        input: CalibSource::Live {
            name: name.to_string(),
        },
        out: job.out.clone(),
        choice: job.choice.clone(),
        viewer: job.viewer.clone(),
        common: job.common.clone(),
        init: calibrate::Start::Nominal,
    };
    let (board, log) = (board.clone(), log.clone());
    let traffic = source.traffic();
    let (read, nominal) = (read.clone(), nominal.clone());
    let values = crate::io::SampleSource::info(source).wheel_values;
    let input = calibrate::LiveInput {
        source,
        wheels: Box::new(move || {
            let n = traffic.lock().map_or(0, |t| t.counts[1]) as usize;
            super::wheels::describe(&read, &nominal, n, values)
        }),
        on_named: Some(Box::new(move |c| {
            if let Ok(mut b) = board.lock() {
                b.named(c, Instant::now());
            }
            say(
                &log,
                &format!("change named: {}", crate::live::status::change_line(c)),
            );
        })),
    };
    calibrate::run_live(&cal_job, input, observer)
}

/// Runs `odocal live` until `stop` is raised (or the network side fails);
/// `log` gets one line per event (status changes, refusals, silences).
pub fn run(job: &LiveJob, stop: Arc<AtomicBool>, log: Log) -> Result<LiveOutcome, PipelineError> {
    let (cfg, nominal) = job.common.load_nominal_open()?;
    let mut read = super::read_options(&cfg, &nominal.robot);
    // Each writer's messages arrive in order: nothing is held back to sort.
    read.reorder_tolerance = 0.0;
    read.log_time_for_unset = false;
    let (domain, localhost) = network(&cfg.live)?;
    let (joined_at, cpu0) = (Instant::now(), cpu_seconds());
    let joined = join(job, &cfg.live, &read, (domain, localhost), &stop)?;
    let log: SharedLog = Arc::new(Mutex::new(log));
    let name = format!("ROS 2 domain {domain}");
    let source_log = log.clone();
    let mut source = LiveSource::start(
        &name,
        joined.rx,
        &joined.subscribed,
        &read,
        &cfg.live,
        stop.clone(),
        joined.stats.clone(),
        Box::new(move |m: &str| say(&source_log, m)),
    )?;
    let start_s = joined_at.elapsed().as_secs_f64();
    let traffic = source.traffic();
    let board = Arc::new(Mutex::new(StatusBoard::new(nominal.kinematics())));
    let node = Arc::new(joined.node);
    let (reporting, done) = report_on(Reporter {
        node: node.clone(),
        publisher: joined.diagnostics,
        board: board.clone(),
        traffic: traffic.clone(),
        stats: joined.stats.clone(),
        params: cfg.live.clone(),
        hardware: job.node.clone(),
        published: 0,
        log: log.clone(),
        last_level: None,
    })?;
    let mut observer = LiveObserver::new(
        joined.odometry,
        (board.clone(), traffic.clone()),
        (cfg.live.odom_frame.clone(), cfg.live.base_frame.clone()),
    );
    let result = calibrate_live(
        job,
        &name,
        &mut source,
        (&read, &nominal),
        (&board, &log),
        &mut observer,
    );
    drop(source);
    done.store(true, Ordering::Relaxed);
    let diagnostics_published = reporting.join().unwrap_or(0);
    stop.store(true, Ordering::Relaxed);
    joined.listener.finish();
    node.stop();
    let calibration = result?;
    let run_s = joined_at.elapsed().as_secs_f64();
    let cpu_s = match (cpu0, cpu_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => f64::NAN,
    };
    let (counts, scans_dropped) = traffic
        .lock()
        .map(|t| (t.counts, t.scans_dropped))
        .unwrap_or_default();
    let report = LiveReport {
        domain,
        localhost_only: localhost,
        start_s,
        run_s,
        cpu_s,
        cpu_share: cpu_s / run_s,
        scan_to_estimate: Latency::of(observer.scan_latency_ms),
        wheel_to_odometry: Latency::of(observer.wheel_latency_ms),
        odometry_published: board.lock().map_or(0, |b| b.odometry),
        diagnostics_published,
        messages: joined.stats.counts(),
        samples: [counts[0], counts[1], counts[2], counts[3]],
        scans_dropped,
    };
    write_report(&job.out, &report)?;
    Ok(LiveOutcome {
        calibration,
        report,
    })
}

/// Writes `DIR/live.json` atomically.
fn write_report(dir: &std::path::Path, report: &LiveReport) -> Result<(), PipelineError> {
    let path = dir.join("live.json");
    let text = serde_json::to_string_pretty(report).map_err(|e| PipelineError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    crate::io::atomic::write_bytes_atomic(&path, text.as_bytes()).map_err(|e| {
        PipelineError::Write {
            path: path.display().to_string(),
            message: e.to_string(),
        }
    })
}
