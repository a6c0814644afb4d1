//! The layout the viewer opens on (a Rerun blueprint, stored first in the
//! recording): the world — map, trajectories, the robot with its laser and
//! scan, the scan-matching ellipses (the latest and the trail of all up to
//! the cursor) — on the left; on the right the wheel
//! radii and the wheel base over time, the particle cloud in the
//! (R_R, R_L) plane and the scan-matching quality over time.

use super::logger::entity;
use rerun::blueprint::{Blueprint, Horizontal, Spatial2DView, TimeSeriesView, Vertical};

/// The blueprint; `ellipse_scale` is named in the world view's title.
pub fn blueprint(ellipse_scale: f64) -> Blueprint {
    let world = Spatial2DView::new(format!(
        "world: map, trajectories, robot, scan (match ellipses 1σ ×{ellipse_scale}, latest and trail)"
    ))
    .with_origin("/world");
    let radii = TimeSeriesView::new("wheel radii (m)")
        .with_origin("/")
        .with_contents([
            format!("+ /{}", entity::EST_R_RIGHT),
            format!("+ /{}", entity::EST_R_LEFT),
        ]);
    let base = TimeSeriesView::new("wheel base (m)")
        .with_origin("/")
        .with_contents([format!("+ /{}", entity::EST_WHEEL_BASE)]);
    let cloud = Spatial2DView::new("particles: R_R (x) against R_L (y), m")
        .with_origin(format!("/{}", entity::PARTICLES));
    let icp = TimeSeriesView::new("scan matching").with_origin("/icp");
    let right = Vertical::new([radii.into(), base.into(), cloud.into(), icp.into()])
        .with_row_shares([1.0, 1.0, 1.5, 1.0]);
    Blueprint::new(Horizontal::new([world.into(), right.into()]).with_column_shares([3.0, 2.0]))
}
