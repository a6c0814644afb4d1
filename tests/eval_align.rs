//! Alignment round trips: a trajectory moved by a random SE(2)/Sim(2)/SE(3)/
//! Sim(3) transform is recovered exactly, and the APE after alignment is 0.

use nalgebra::{Isometry3, Similarity3, Translation3, UnitQuaternion};
use odocal::eval::align::apply;
use odocal::eval::{self, Alignment, EvalError, EvalOptions, Trajectory3};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use std::f64::consts::PI;

/// A wandering 3D (or planar, z = 0 and yaw only) trajectory at 10 Hz.
fn wander(rng: &mut StdRng, n: usize, planar: bool) -> Trajectory3 {
    let (mut x, mut y, mut z, mut th) = (0.0, 0.0, 0.0, 0.0);
    let mut stamps = Vec::new();
    let mut poses = Vec::new();
    for i in 0..n {
        th += rng.random_range(-0.2..0.2);
        x += 0.3 * f64::cos(th);
        y += 0.3 * f64::sin(th);
        let (roll, pitch) = if planar {
            (0.0, 0.0)
        } else {
            z += rng.random_range(-0.05..0.05);
            (rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1))
        };
        stamps.push(i as f64 * 0.1);
        poses.push(Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(roll, pitch, th),
        ));
    }
    Trajectory3::from_parts(stamps, poses).unwrap()
}

fn random_transform(rng: &mut StdRng, kind: Alignment) -> Similarity3<f64> {
    let planar = matches!(kind, Alignment::Se2 | Alignment::Sim2);
    let scale = if matches!(kind, Alignment::Sim2 | Alignment::Sim3) {
        rng.random_range(0.3..3.0)
    } else {
        1.0
    };
    let rot = if planar {
        UnitQuaternion::from_euler_angles(0.0, 0.0, rng.random_range(-PI..PI))
    } else {
        UnitQuaternion::from_euler_angles(
            rng.random_range(-PI..PI),
            rng.random_range(-1.5..1.5),
            rng.random_range(-PI..PI),
        )
    };
    let z = if planar {
        0.0
    } else {
        rng.random_range(-20.0..20.0)
    };
    let t = Translation3::new(
        rng.random_range(-50.0..50.0),
        rng.random_range(-50.0..50.0),
        z,
    );
    Similarity3::from_parts(t, rot, scale)
}

#[test]
fn eval_alignment_recovers_random_transforms_exactly() {
    let mut rng = StdRng::seed_from_u64(2024);
    let kinds = [
        Alignment::Se2,
        Alignment::Sim2,
        Alignment::Se3,
        Alignment::Sim3,
    ];
    let mut checked = 0;
    for kind in kinds {
        for _ in 0..25 {
            let planar = matches!(kind, Alignment::Se2 | Alignment::Sim2);
            let truth = wander(&mut rng, 200, planar);
            let moved_by = random_transform(&mut rng, kind);
            let moved = Trajectory3::from_parts(
                truth.stamps.clone(),
                truth.poses.iter().map(|p| apply(&moved_by, p)).collect(),
            )
            .unwrap();
            let opts = EvalOptions {
                align: kind,
                ..Default::default()
            };
            let r = eval::evaluate(&moved, Some(&truth), None, &opts).unwrap();
            let m = r.trajectory.unwrap();
            let d = r.detail.unwrap();
            assert_eq!(m.matched, 200);
            // The fitted reference_from_estimate undoes the applied transform.
            let undo = d.transform * moved_by;
            assert!(
                (undo.scaling() - 1.0).abs() < 1e-9,
                "{kind:?} scale {}",
                undo.scaling()
            );
            assert!(
                undo.isometry.translation.vector.norm() < 1e-8,
                "{kind:?} {undo}"
            );
            assert!(undo.isometry.rotation.angle() < 1e-9, "{kind:?} {undo}");
            assert!(
                m.ape.max < 1e-8 && m.ape_rot_deg.unwrap().max < 1e-6,
                "{kind:?} {:?}",
                m.ape
            );
            assert!(m.rpe.max < 1e-8 && m.final_error < 1e-8);
            checked += 1;
        }
    }
    assert_eq!(checked, 100, "enough random cases ran");
}

#[test]
fn eval_planar_alignment_ignores_what_it_cannot_fix() {
    // SE(2) cannot undo a roll: the error stays; SE(3) removes it.
    let mut rng = StdRng::seed_from_u64(5);
    let truth = wander(&mut rng, 100, false);
    let tilt = Similarity3::from_parts(
        Translation3::new(1.0, 2.0, 0.0),
        UnitQuaternion::from_euler_angles(0.3, 0.0, 0.5),
        1.0,
    );
    let moved = Trajectory3::from_parts(
        truth.stamps.clone(),
        truth.poses.iter().map(|p| apply(&tilt, p)).collect(),
    )
    .unwrap();
    let run = |align| {
        eval::evaluate(
            &moved,
            Some(&truth),
            None,
            &EvalOptions {
                align,
                ..Default::default()
            },
        )
        .unwrap()
        .trajectory
        .unwrap()
    };
    assert!(run(Alignment::Se2).ape_rot_deg.unwrap().min > 10.0);
    assert!(run(Alignment::Se3).ape.max < 1e-8);
    // Origin alignment: the first poses coincide, so the rigid motion is gone.
    assert!(run(Alignment::Origin).ape.max < 1e-8);
    assert!(run(Alignment::None).ape.min > 0.1);
}

#[test]
fn eval_alignment_refuses_degenerate_points() {
    // All positions on one line: SE(3) is undetermined (rank 1).
    let line = Trajectory3::from_parts(
        (0..10).map(|i| i as f64).collect(),
        (0..10)
            .map(|i| Isometry3::translation(i as f64, 0.0, 0.0))
            .collect(),
    )
    .unwrap();
    let r = eval::evaluate(
        &line,
        Some(&line),
        None,
        &EvalOptions {
            align: Alignment::Se3,
            ..Default::default()
        },
    );
    assert!(matches!(r, Err(EvalError::DegenerateAlignment(_))), "{r:?}");
    // A standing robot: no SE(2) either.
    let still = Trajectory3::from_parts(
        (0..10).map(|i| i as f64).collect(),
        vec![Isometry3::translation(1.0, 1.0, 0.0); 10],
    )
    .unwrap();
    let r = eval::evaluate(
        &still,
        Some(&still),
        None,
        &EvalOptions {
            align: Alignment::Sim2,
            ..Default::default()
        },
    );
    assert!(matches!(r, Err(EvalError::DegenerateAlignment(_))), "{r:?}");
}
