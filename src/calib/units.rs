//! The units \[Farina\]'s printed settings are in, which odocal's settings
//! (in wheel radii, per √s) are converted from.

/// The wheel radius (m) of \[Farina\]'s wheelchair, the unit its printed
/// noise values are in.
pub const PAPER_RADIUS_M: f64 = 0.32;

/// The step (s) its printed per-iteration noise values are taken at: one
/// scan of its LMS111 at 50 Hz. odocal's random walks are per √s, so that
/// the filters follow a change as fast whatever their step rate (one scan
/// pair, or an interval of a second); the defaults are the paper's values
/// divided by √0.02.
pub const PAPER_STEP_S: f64 = 0.02;

/// √[`PAPER_STEP_S`].
pub const SQRT_PAPER_STEP: f64 = 0.141_421_356_237_309_5;
