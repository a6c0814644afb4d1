//! Scan matching: 2D point-to-line ICP of each scan against a small local map
//! of recent keyframes (or the previous scan), giving the motion of the robot
//! base with a 3×3 covariance and quality flags.
//!
//! Pipeline of one pair (each step a file):
//! - `preprocess`: REP 117-valid readings within range limits, in the base
//!   frame via `base_from_laser`, motion-compensated over the sweep (deskew by
//!   the prior's twist), with surface links between neighbouring beams;
//!   optional beam stride / voxel thinning of the source scan.
//! - `reference`: the local map (or previous scan) with a line fitted through
//!   every point's surface neighbourhood (at most `normal_window + 1` beams,
//!   and about `normal_length` m of surface) and a nearest-neighbour index
//!   (`neighbours`: the uniform grid of `grid`, or kiddo's k-d tree), built once.
//! - `metric`: the point-to-line error and its Jacobian, shared by
//!   registration and covariance; point-to-point (`[icp] metric`) as the
//!   same error twice over.
//! - `register`: foot on the nearest point's fitted line + Geman–McClure
//!   weights + Gauss–Newton steps, until the pose change is below
//!   `convergence`, with a weak prior term at the odometry guess that holds
//!   the directions the geometry leaves loose (corridors). Fitted lines
//!   rather than the raw polyline keep the range noise of the reference out
//!   of the estimate (the zigzag polyline made motions ~2 % short).
//! - `threshold`: the adaptive gate of KISS-ICP \[Vizzo2023\] from the prior's recent error.
//! - `prior_model`: the odometry's and the constant-velocity guess's errors
//!   against the matched motions, learned per recording; the prior term is
//!   centred on their inverse-variance blend (`prior_blend_rate`).
//! - `covariance`: Hessian × residual variance × inflation; the choice and the
//!   inflation are explained there; and the information measured beyond the
//!   fitted lines' direction noise (range noise tilts short line fits, which
//!   looks like information along a featureless wall), which decides how
//!   much of each direction a motion owes to the scan and how much to the
//!   prior term (`matcher/split`).
//! - `limits`: the robot's speed and turn-rate limits, the plausibility gate
//!   of every match.
//! - `matcher`: the pair-by-pair [`ScanMatcher`], a short loop over its
//!   components, each in its own file with its own settings: prior
//!   selection (`prior`, `prior_term`), the source (`source`), one
//!   registration (`attempt`), retries of failed matches from the motion
//!   guesses (`retry`), the gates and failure flags (`acceptance`), and a
//!   local map kept across a few failed scans (`local_map`); `stream`: the
//!   incremental [`StreamMatcher`] (scan in, motion out) that builds the
//!   odometry prior from wheel or odometry samples as they arrive; `run`:
//!   whole recordings ([`match_recording`], a loop over it), [`Tally`],
//!   [`summarise`] and [`integrate`]. Two guards against a wrong odometry prior: an odometry
//!   that stands still while the robot cannot have stopped (a frozen
//!   reading) is replaced by the constant-velocity guess, also for the jump
//!   that follows, the scans choosing between the two; and a match whose
//!   scan-only estimate contradicts the prior term (χ² test on the
//!   innovation, 99.9 %) is matched again without it.
//!
//! Failed pairs (too few points or correspondences, not converged, degenerate,
//! bad time, inconsistent beams, implausible jump vs the prior, first match
//! after failed scans) carry
//! `Motion::failure`, so `VelocityObs::from_motion` never turns them into
//! observations.

// `!(x > 0.0)` is deliberate throughout: it is true for NaN as well.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod covariance;
mod grid;
mod limits;
mod matcher;
mod metric;
mod neighbours;
mod params;
mod preprocess;
mod prior_model;
mod prior_scale;
mod reference;
mod register;
mod run;
mod stream;
mod threshold;
mod time_offset;

pub use covariance::MIN_RESIDUAL_STD;
pub use limits::SpeedLimits;
pub use matcher::{MatchInfo, PriorSource, ScanMatcher};
pub use metric::Metric;
pub use neighbours::NeighbourSearch;
pub use params::{IcpParams, IcpParamsError, PriorChoice};
pub use preprocess::{Preprocessor, ScanPoints};
pub use prior_scale::PriorScale;
pub use run::{integrate, match_recording, summarise, IcpStats, Tally};
pub use stream::{PoseWindow, Prior, StreamMatcher};
pub use threshold::AdaptiveThreshold;
pub use time_offset::TimeOffsetFit;
