//! Speed of the classic calibrators: the seed-002 GA on 15 short runs and the
//! heading-fusion particle filter over a 22 m path.

use criterion::{criterion_group, criterion_main, Criterion};
use odocal::classic::{
    drive_segments, ga_calibrate, heading_pf, irregular_path, simulate_heading, DriveParams,
    GaParams, HeadingPfParams, HeadingSourceParams,
};
use odocal::experiments::{calibration_runs, PfExperimentParams};
use odocal::geom::Pose2;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let p = PfExperimentParams::default();
    let tpr = p.ticks_per_rev;
    let truth = p.truth.to_diff_drive(tpr);
    let runs = calibration_runs(
        &p.uncalibrated.to_diff_drive(tpr),
        &truth,
        15,
        tpr,
        &p.drive,
        1,
    );
    c.bench_function("ga_15_runs_150_generations", |b| {
        b.iter(|| ga_calibrate(black_box(&runs), &GaParams::default()).unwrap())
    });
    let run = drive_segments(
        &truth,
        &truth,
        &irregular_path(22.0, 1),
        &DriveParams::default(),
        1,
    );
    let h = simulate_heading(&run.truth, &HeadingSourceParams::default(), 1);
    c.bench_function("heading_pf_22m_500_particles", |b| {
        b.iter(|| {
            heading_pf(
                &truth,
                black_box(&run.wheels),
                &h,
                &Pose2::identity(),
                &HeadingPfParams::default(),
            )
            .unwrap()
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
