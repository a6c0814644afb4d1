//! What sees a run as it goes: the files it writes, a Rerun recording, a
//! progress bar, the in-memory results. Each is a [`RunObserver`] of the one
//! driver ([`super::drive`]), whatever the input's format.

use crate::calib::{CloudView, Estimate};
use crate::geom::Pose2;
use crate::io::{Item, StreamInfo};
use crate::motion::Motion;

/// Sees a run as it goes. Every method has a no-op default; calls come in the
/// run's order, and an observer keeps (and reports) its own failures.
pub trait RunObserver {
    /// The run starts on a source with these streams (known before any sample).
    fn start(&mut self, _info: &StreamInfo) {}
    /// A sample read from the source, in the order the source yields it.
    fn item(&mut self, _item: &Item) {}
    /// A pose of the integrated ICP trajectory (odometry frame) at `t` (s).
    fn icp_pose(&mut self, _t: f64, _pose: &Pose2) {}
    /// A scan pair matched or flagged by ICP.
    fn motion(&mut self, _motion: &Motion) {}
    /// A filter step: its estimate and, for particle filters, the cloud.
    fn step(&mut self, _estimate: &Estimate, _cloud: Option<CloudView<'_>>) {}
    /// A pose of the calibrated odometry (odometry frame) at `t` (s).
    fn calibrated_pose(&mut self, _t: f64, _pose: &Pose2) {}
    /// After a filter step ending at `t` (s) behind the online front end:
    /// the time offset in use (s, wheel stamp minus laser stamp of one
    /// instant) and the laser mounting `[x (m), y (m), yaw (rad)]`.
    fn front(&mut self, _t: f64, _time_offset_s: f64, _laser: [f64; 3]) {}
}

/// An observer that ignores the run.
pub struct NoObserver;

impl RunObserver for NoObserver {}

/// Several observers, each told everything in turn.
#[derive(Default)]
pub struct Observers<'a>(pub Vec<&'a mut dyn RunObserver>);

impl RunObserver for Observers<'_> {
    fn start(&mut self, info: &StreamInfo) {
        self.0.iter_mut().for_each(|o| o.start(info));
    }
    fn item(&mut self, item: &Item) {
        self.0.iter_mut().for_each(|o| o.item(item));
    }
    fn icp_pose(&mut self, t: f64, pose: &Pose2) {
        self.0.iter_mut().for_each(|o| o.icp_pose(t, pose));
    }
    fn motion(&mut self, motion: &Motion) {
        self.0.iter_mut().for_each(|o| o.motion(motion));
    }
    fn step(&mut self, estimate: &Estimate, cloud: Option<CloudView<'_>>) {
        self.0.iter_mut().for_each(|o| o.step(estimate, cloud));
    }
    fn calibrated_pose(&mut self, t: f64, pose: &Pose2) {
        self.0.iter_mut().for_each(|o| o.calibrated_pose(t, pose));
    }
    fn front(&mut self, t: f64, time_offset_s: f64, laser: [f64; 3]) {
        self.0
            .iter_mut()
            .for_each(|o| o.front(t, time_offset_s, laser));
    }
}

/// Counts the scans read, for a progress display: `progress` gets the
/// fraction of the source's scans read so far.
pub struct Progress<F: FnMut(f64)> {
    scans: usize,
    read: usize,
    progress: F,
}

impl<F: FnMut(f64)> Progress<F> {
    /// Reports to `progress`.
    pub fn new(progress: F) -> Self {
        Self {
            scans: 0,
            read: 0,
            progress,
        }
    }
}

impl<F: FnMut(f64)> RunObserver for Progress<F> {
    fn start(&mut self, info: &StreamInfo) {
        self.scans = info.scans;
    }
    fn item(&mut self, item: &Item) {
        if matches!(item, Item::Scan(_)) {
            self.read += 1;
            (self.progress)(self.read as f64 / self.scans.max(1) as f64);
        }
    }
}
