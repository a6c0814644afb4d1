//! Trajectory evaluation against a reference, with evo's definitions
//! (github.com/MichaelGrupp/evo, 1.38): time association, Umeyama alignment,
//! absolute and relative pose errors; plus the papers' figures (RMSE x,y and θ,
//! drift in % of distance travelled, final-position error) and the relation
//! metric of Kümmerle et al. 2009.
//!
//! Layers as in evo: [`sync`] pairs poses by time, [`align()`] fits the
//! estimate onto the reference, [`ape()`] / [`rpe()`] / [`relations()`] measure,
//! [`evaluate`] runs them all for the command line. Pure functions over
//! trajectories; reading files is `io`'s job.

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

pub use align::{align, alignment_transform, Alignment};
pub use ape::{ape, Ape};
pub use error::EvalError;
pub use relations::{relations, Relation, RelationError, RelationStats, RelationSummary};
pub use report::{evaluate, EvalDetail, EvalOptions, EvalReport, TrajectoryMetrics};
pub use rpe::{rpe, DeltaUnit, Rpe, RpeDelta};
pub use stats::Stats;
pub use sync::{sync, Matched, SyncOptions};
pub use traj3::{Pose3, Trajectory3};
