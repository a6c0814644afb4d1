//! Trajectory evaluation against a reference, with evo's definitions
//! (\[Grupp2017\], github.com/MichaelGrupp/evo, 1.38): time association, Umeyama alignment,
//! absolute and relative pose errors; plus the papers' figures (RMSE x,y and θ,
//! drift in % of distance travelled, final-position error) and the relation
//! metric of \[Kummerle2009\].
//!
//! Layers as in evo: [`sync`](mod@sync) pairs poses by time, [`align()`] fits the
//! estimate onto the reference, [`ape()`] / [`rpe()`] / [`relations()`] measure,
//! [`evaluate`] runs them all for the command line. Pure functions over
//! trajectories; reading files is `io`'s job.
//!
//! ```
//! use odocal::eval::{evaluate, Alignment, EvalOptions, Trajectory3};
//! use odocal::geom::pose;
//! use odocal::traj::Trajectory;
//!
//! let mut truth = Trajectory::default();
//! let mut odom = Trajectory::default();
//! for i in 0..100 {
//!     let t = i as f64 * 0.1;
//!     truth.push(t, pose(t.cos(), t.sin(), t + 1.57));
//!     odom.push(t, pose(1.02 * t.cos(), 1.02 * t.sin(), t + 1.57)); // 2 % too long
//! }
//! let opts = EvalOptions { align: Alignment::Sim2, ..Default::default() };
//! let r = evaluate(&Trajectory3::from_2d(&odom), Some(&Trajectory3::from_2d(&truth)), None, &opts)?;
//! let m = r.trajectory.unwrap();
//! assert_eq!(m.matched, 100);
//! assert!(m.ape.rmse < 1e-9); // Sim(2) absorbs the scale error
//! # Ok::<(), odocal::eval::EvalError>(())
//! ```

pub mod align;
pub mod ape;
mod error;
pub mod relations;
pub mod report;
pub mod rpe;
pub mod stats;
pub mod sync;
pub mod traj3;
pub mod umeyama;
pub mod windowed;

pub use align::{align, alignment_transform, origin_by_heading, resolve, Alignment};
pub use ape::{ape, Ape};
pub use error::EvalError;
pub use relations::{relations, Relation, RelationError, RelationStats, RelationSummary};
pub use report::{
    evaluate, AlignmentUsed, EvalDetail, EvalOptions, EvalReport, PairingUsed, TrajectoryMetrics,
};
pub use rpe::{rpe, rpe_positions, DeltaUnit, Rpe, RpeDelta};
pub use stats::Stats;
pub use sync::{resample, sync, Matched, SyncOptions};
pub use traj3::{trajectory_from_stamped, Pose3, Trajectory3};
pub use windowed::{windowed_error, WheelIncrement, WindowedError};
