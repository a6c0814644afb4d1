//! Why an evaluation cannot produce numbers: the inputs do not overlap, too few
//! poses match, an alignment is degenerate, or an option is out of range.

/// Every way `eval` refuses to produce a result (never a NaN instead).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// A trajectory has fewer poses than the step needs.
    #[error("{what} has {count} pose(s); at least {needed} are needed")]
    TooFewPoses {
        /// Which input ("estimate", "reference").
        what: &'static str,
        /// Poses it has.
        count: usize,
        /// Poses needed.
        needed: usize,
    },
    /// The two trajectories' time spans do not overlap (after the offset).
    #[error(
        "no overlapping time range: estimate {est_start:.6}..{est_end:.6} s, \
         reference {ref_start:.6}..{ref_end:.6} s (offset {offset} s)"
    )]
    NoOverlap {
        /// First estimate stamp (s).
        est_start: f64,
        /// Last estimate stamp (s).
        est_end: f64,
        /// First reference stamp (s).
        ref_start: f64,
        /// Last reference stamp (s).
        ref_end: f64,
        /// Offset added to the estimate stamps (s).
        offset: f64,
    },
    /// Association found fewer pose pairs than needed.
    #[error(
        "only {matched} pose pair(s) matched within {max_diff} s (offset {offset} s); \
         at least {needed} are needed"
    )]
    TooFewMatches {
        /// Pairs found.
        matched: usize,
        /// Pairs needed.
        needed: usize,
        /// Maximum stamp difference used (s).
        max_diff: f64,
        /// Offset used (s).
        offset: f64,
    },
    /// Resampling the reference found fewer estimate stamps than needed.
    #[error(
        "only {paired} estimate stamp(s) lie inside the reference's span with reference \
         samples at most {max_gap} s apart around them (offset {offset} s); at least 2 are needed"
    )]
    TooFewResampled {
        /// Stamps paired.
        paired: usize,
        /// Largest reference gap bridged (s).
        max_gap: f64,
        /// Offset used (s).
        offset: f64,
    },
    /// The point sets do not determine an alignment (e.g. all positions equal
    /// or on one line for a 3D alignment).
    #[error("degenerate alignment: {0}")]
    DegenerateAlignment(String),
    /// The RPE delta selects no pose pair.
    #[error("RPE delta {delta} {unit} selects no pose pair")]
    NoRpePairs {
        /// Delta value.
        delta: f64,
        /// Its unit.
        unit: &'static str,
    },
    /// No relation lies inside the trajectory's time span.
    #[error("none of the {total} relations lies inside the trajectory's time span")]
    NoRelations {
        /// Relations given.
        total: usize,
    },
    /// An input holds a NaN or infinite value.
    #[error("{what} contains a non-finite value at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the first bad pose.
        index: usize,
    },
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
}
