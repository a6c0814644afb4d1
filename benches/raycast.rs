//! Ray-casting throughput of the simulator's worlds: one full 541-beam LMS111
//! scan (270°, 0.5°) per iteration, in the corridor loop and in a
//! ~2000-segment cluttered world. Rays/s = 541 / time per iteration.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::Point2;
use odocal::sim::{worlds, World};
use std::hint::black_box;

fn scan_bench(c: &mut Criterion, label: &str, world: &World, origins: &[Point2<f64>]) {
    let mut g = c.benchmark_group("raycast");
    g.throughput(Throughput::Elements(541));
    let mut out = vec![0.0; 541];
    let mut k = 0usize;
    g.bench_function(format!("{label}_541_beams"), |b| {
        b.iter(|| {
            let o = origins[k % origins.len()];
            k += 1;
            let first = k as f64 * 0.37 - 135f64.to_radians();
            world.cast_fan(o, first, 0.5f64.to_radians(), 20.0, &mut out);
            black_box(&out);
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    let corridor = worlds::builtin("corridor-loop").unwrap();
    let pts: Vec<_> = (0..64)
        .map(|i| {
            let s = i as f64 / 64.0 * 90.0;
            // Walk the corridor centre line.
            let (x, y) = if s < 27.5 {
                (1.25 + s, 1.25)
            } else if s < 45.0 {
                (28.75, 1.25 + s - 27.5)
            } else if s < 72.5 {
                (28.75 - (s - 45.0), 18.75)
            } else {
                (1.25, 18.75 - (s - 72.5))
            };
            Point2::new(x, y)
        })
        .collect();
    scan_bench(c, "corridor_loop", &corridor, &pts);
    let clutter = worlds::cluttered(2000, 7);
    let free: Vec<_> = (0..400)
        .map(|i| Point2::new(2.0 + (i % 20) as f64 * 1.9, 2.0 + (i / 20) as f64 * 1.9))
        .filter(|p| clutter.distance(*p) > 0.3)
        .collect();
    scan_bench(c, "cluttered_2000", &clutter, &free);
}

criterion_group!(raycast, benches);
criterion_main!(raycast);
