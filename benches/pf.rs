//! One particle-filter step with 8,000 particles (design.md: ≤ 0.1 ms).

use criterion::{criterion_group, criterion_main, Criterion};
use odocal::calib::{CalibParams, CalibStep, Calibrator, Kind, Method, ParticleFilter, Trigger};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    // Wheel rates and measurements of a chair at ~1 m/s turning gently,
    // consistent with the filter's default ranges.
    let step = CalibStep::new(0.0, 0.02, 3.1, 2.9)
        .with(Kind::W, 0.095, 0.003)
        .with(Kind::V, 0.97, 0.05)
        .with(Kind::W, 0.096, 0.01);
    for (label, method, trigger) in [
        ("pf_step_8000_neff", Method::Pf, Trigger::Neff),
        ("pf_step_8000_resample_every", Method::Pf, Trigger::Every),
        (
            "adaptive_pf_step_8000_neff",
            Method::AdaptivePf,
            Trigger::Neff,
        ),
    ] {
        let mut p = CalibParams {
            method,
            trigger,
            particles: Some(8000),
            ..Default::default()
        };
        // Keep the adaptive filter at 8,000 particles.
        p.adaptive.n_min = 8000;
        p.adaptive.n_max = 8000;
        let mut pf = ParticleFilter::new(&p);
        c.bench_function(label, |b| b.iter(|| black_box(pf.step(black_box(&step)))));
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
