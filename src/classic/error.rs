//! Errors of the classic calibration methods.

/// Data a classic method cannot use (too few rows, degenerate values).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClassicError {
    /// Not enough data points for the fit or test.
    #[error("{method}: need at least {needed} {what}, got {got}")]
    TooFew {
        /// The method asking.
        method: &'static str,
        /// What is counted.
        what: &'static str,
        /// Minimum count.
        needed: usize,
        /// Count given.
        got: usize,
    },
    /// A value is not finite or out of its physical range.
    #[error("{method}: {message}")]
    Invalid {
        /// The method asking.
        method: &'static str,
        /// What is wrong.
        message: String,
    },
}

impl ClassicError {
    /// Shorthand for [`ClassicError::Invalid`].
    pub(crate) fn invalid(method: &'static str, message: impl Into<String>) -> Self {
        Self::Invalid {
            method,
            message: message.into(),
        }
    }
}

/// Checks that every value is finite, naming the first that is not.
pub(crate) fn check_finite(
    method: &'static str,
    what: &str,
    values: impl IntoIterator<Item = f64>,
) -> Result<(), ClassicError> {
    for (i, v) in values.into_iter().enumerate() {
        if !v.is_finite() {
            return Err(ClassicError::invalid(
                method,
                format!("{what} #{i} is not finite ({v})"),
            ));
        }
    }
    Ok(())
}
