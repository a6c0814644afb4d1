//! One particle-filter step with 8,000 particles (design.md: ≤ 0.1 ms), and
//! the Adaptive-PF's step at the particle counts its dispersion rule takes
//! over a run ([Farina, Fig. 5]: time per iteration falls with N).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use odocal::calib::{CalibParams, CalibStep, Calibrator, Kind, Method, ParticleFilter, Trigger};
use std::hint::black_box;

/// Wheel rates and measurements of a chair at ~1 m/s turning gently,
/// consistent with the filter's default ranges.
fn step() -> CalibStep {
    CalibStep::new(0.0, 0.02, 3.1, 2.9)
        .with(Kind::W, 0.095, 0.003)
        .with(Kind::V, 0.97, 0.05)
        .with(Kind::W, 0.096, 0.01)
}

/// A filter held at `n` particles.
fn filter(method: Method, trigger: Trigger, n: usize) -> ParticleFilter {
    let mut p = CalibParams {
        method,
        trigger,
        particles: Some(n),
        ..Default::default()
    };
    p.adaptive.n_min = n;
    p.adaptive.n_max = n;
    ParticleFilter::new(&p.pf_settings())
}

fn bench(c: &mut Criterion) {
    let step = step();
    for (label, method, trigger) in [
        ("pf_step_8000_neff", Method::Pf, Trigger::Neff),
        ("pf_step_8000_resample_every", Method::Pf, Trigger::Every),
        (
            "adaptive_pf_step_8000_neff",
            Method::AdaptivePf,
            Trigger::Neff,
        ),
    ] {
        let mut pf = filter(method, trigger, 8000);
        c.bench_function(label, |b| b.iter(|| black_box(pf.step(black_box(&step)))));
    }
    // The counts the dispersion rule gives from the uniform start (10,400)
    // down to a converged cloud (~400).
    let mut g = c.benchmark_group("adaptive_pf_step_by_particles");
    for n in [400usize, 1000, 2000, 4000, 8000, 16000] {
        let mut pf = filter(Method::AdaptivePf, Trigger::Neff, n);
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| black_box(pf.step(black_box(&step))))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
