//! Scan matching: 2D point-to-point ICP between consecutive laser scans (or
//! against a small local map of recent keyframes), giving the motion of the
//! robot base with a 3×3 covariance and quality flags.
//!
//! Pipeline of one pair (each step a file):
//! - `preprocess`: REP 117-valid readings within range limits, in the base
//!   frame via `base_from_laser`, with surface links between neighbouring beams;
//!   optional beam stride / voxel thinning of the source scan.
//! - `reference`: the previous scan (or local map) with a kd-tree built once.
//! - `register`: closest point on the reference polyline + Geman–McClure
//!   weights + closed-form alignment (`align`), until the pose change is below
//!   `convergence`. Matching against the polyline rather than its vertices
//!   keeps the estimate free of the beam-sampling bias that makes vertex-only
//!   ICP stick to zero motion along walls.
//! - `threshold`: KISS-ICP's adaptive gate from the prior's recent error.
//! - `covariance`: Hessian × residual variance × inflation; the choice and the
//!   inflation are explained there.
//! - `matcher`: the streaming [`ScanMatcher`] with prior selection and
//!   failure flags; `run`: whole recordings and [`integrate`].
//!
//! Failed pairs (too few points or correspondences, not converged, degenerate,
//! bad time, inconsistent beams, implausible jump vs the prior) carry
//! `Motion::failure`, so `VelocityObs::from_motion` never turns them into
//! observations.

mod align;
mod covariance;
mod matcher;
mod params;
mod preprocess;
mod reference;
mod register;
mod run;
mod threshold;

pub use align::Aligner;
pub use covariance::MIN_RESIDUAL_STD;
pub use matcher::{MatchInfo, PriorSource, ScanMatcher};
pub use params::{IcpParams, IcpParamsError};
pub use preprocess::{Preprocessor, ScanPoints};
pub use run::{integrate, match_recording, summarise, IcpStats};
pub use threshold::AdaptiveThreshold;
