//! The square test of [Paryanto, Table III]: the corners of a square path as
//! estimated by odometry next to the actual corners; corner errors and the
//! closure error at the return to the start.

use super::error::{check_finite, ClassicError};
use serde::Serialize;
use std::fmt::Write;

/// One corner: odometry estimate and actual position (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SquareCorner {
    /// Odometry x (m).
    pub odom_x: f64,
    /// Odometry y (m).
    pub odom_y: f64,
    /// Actual x (m).
    pub actual_x: f64,
    /// Actual y (m).
    pub actual_y: f64,
}

/// The error at one corner (odometry − actual, m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CornerError {
    /// The corner as given.
    pub corner: SquareCorner,
    /// odom_x − actual_x (m).
    pub dx: f64,
    /// odom_y − actual_y (m).
    pub dy: f64,
    /// Euclidean error (m).
    pub error: f64,
}

/// Corner errors, side lengths and closure error of a square test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SquareReport {
    /// Every corner in order, the first being the start.
    pub corners: Vec<CornerError>,
    /// Lengths of the odometry sides (m).
    pub odom_sides: Vec<f64>,
    /// Lengths of the actual sides (m).
    pub actual_sides: Vec<f64>,
    /// Closure error in x at the last corner (m), odometry − actual.
    pub closure_dx: f64,
    /// Closure error in y (m).
    pub closure_dy: f64,
    /// Euclidean closure error (m).
    pub closure_error: f64,
    /// Closure error as % of the actual path length.
    pub closure_percent: f64,
    /// Largest corner error (m).
    pub max_corner_error: f64,
}

/// Builds the report from the corners (at least start and one more).
pub fn square_report(corners: &[SquareCorner]) -> Result<SquareReport, ClassicError> {
    const M: &str = "square test";
    if corners.len() < 2 {
        return Err(ClassicError::TooFew {
            method: M,
            what: "corners",
            needed: 2,
            got: corners.len(),
        });
    }
    check_finite(
        M,
        "coordinate",
        corners
            .iter()
            .flat_map(|c| [c.odom_x, c.odom_y, c.actual_x, c.actual_y]),
    )?;
    let errs: Vec<CornerError> = corners
        .iter()
        .map(|c| {
            let (dx, dy) = (c.odom_x - c.actual_x, c.odom_y - c.actual_y);
            CornerError {
                corner: *c,
                dx,
                dy,
                error: dx.hypot(dy),
            }
        })
        .collect();
    let sides = |f: fn(&SquareCorner) -> (f64, f64)| -> Vec<f64> {
        corners
            .windows(2)
            .map(|w| {
                let (a, b) = (f(&w[0]), f(&w[1]));
                (b.0 - a.0).hypot(b.1 - a.1)
            })
            .collect()
    };
    let odom_sides = sides(|c| (c.odom_x, c.odom_y));
    let actual_sides = sides(|c| (c.actual_x, c.actual_y));
    let last = errs[errs.len() - 1];
    let length: f64 = actual_sides.iter().sum();
    Ok(SquareReport {
        max_corner_error: errs.iter().fold(0.0, |m, e| m.max(e.error)),
        corners: errs,
        odom_sides,
        closure_dx: last.dx,
        closure_dy: last.dy,
        closure_error: last.error,
        closure_percent: if length > 0.0 {
            100.0 * last.error / length
        } else {
            0.0
        },
        actual_sides,
    })
}

impl SquareReport {
    /// The report as a markdown table in the layout of [Paryanto, Table III],
    /// with the errors added.
    pub fn markdown(&self) -> String {
        let mut s = String::from(
            "| corner | odometry x (m) | odometry y (m) | actual x (m) | actual y (m) | error x (m) | error y (m) | error (m) |\n|---|---|---|---|---|---|---|---|\n",
        );
        for (i, e) in self.corners.iter().enumerate() {
            let c = e.corner;
            let _ = writeln!(
                s,
                "| {i} | {:.2} | {:.2} | {:.2} | {:.2} | {:+.2} | {:+.2} | {:.2} |",
                c.odom_x, c.odom_y, c.actual_x, c.actual_y, e.dx, e.dy, e.error
            );
        }
        let _ = writeln!(
            s,
            "\nClosure error: x {:+.2} m, y {:+.2} m, {:.2} m ({:.2} % of {:.1} m).",
            self.closure_dx,
            self.closure_dy,
            self.closure_error,
            self.closure_percent,
            self.actual_sides.iter().sum::<f64>()
        );
        s
    }
}
