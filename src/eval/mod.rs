//! Trajectory evaluation against a reference, with evo's definitions
//! (github.com/MichaelGrupp/evo, 1.38): time association, Umeyama alignment,
//! absolute and relative pose errors; plus the papers' figures (RMSE x,y and θ,
//! drift in % of distance travelled, final-position error) and the relation
//! metric of Kümmerle et al. 2009.
//!
//! Pure functions over trajectories; reading files is `io`'s job.

mod error;
pub mod relations;
pub mod stats;

pub use error::EvalError;
pub use relations::{relations, Relation, RelationError, RelationStats, RelationSummary};
pub use stats::Stats;
