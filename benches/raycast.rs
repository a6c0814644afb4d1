//! Ray-casting throughput of the simulator's worlds: one full 541-beam LMS111
//! scan (270°, 0.5°) per iteration, in the corridor loop and in a
//! ~2000-segment cluttered world. Rays/s = 541 / time per iteration. Also
//! the whole default simulation (120 s corridor loop).
//!
//! The `raycast_cpu` group measures the thread's CPU time instead of wall
//! time, so the one-core figure holds on a shared, loaded machine.

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::Point2;
use odocal::robot::RobotConfig;
use odocal::sim::{simulate, worlds, SimConfig, World};
use std::hint::black_box;

/// CPU time (ns) consumed by the calling thread.
struct ThreadCpu;

fn thread_cpu_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we own.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

impl Measurement for ThreadCpu {
    type Intermediate = u64;
    type Value = u64;
    fn start(&self) -> u64 {
        thread_cpu_ns()
    }
    fn end(&self, i: u64) -> u64 {
        thread_cpu_ns() - i
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, v: &u64) -> f64 {
        *v as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        static WALL: WallTime = WallTime;
        WALL.formatter()
    }
}

fn scan_bench<M: Measurement>(
    c: &mut Criterion<M>,
    group: &str,
    label: &str,
    world: &World,
    origins: &[Point2<f64>],
) {
    let mut g = c.benchmark_group(group);
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

fn worlds_and_origins() -> Vec<(&'static str, World, Vec<Point2<f64>>)> {
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
    let clutter = worlds::cluttered(2000, 7);
    let free: Vec<_> = (0..400)
        .map(|i| Point2::new(2.0 + (i % 20) as f64 * 1.9, 2.0 + (i / 20) as f64 * 1.9))
        .filter(|p| clutter.distance(*p) > 0.3)
        .collect();
    vec![
        ("corridor_loop", corridor, pts),
        ("cluttered_2000", clutter, free),
    ]
}

fn wall_time(c: &mut Criterion) {
    for (label, world, origins) in worlds_and_origins() {
        scan_bench(c, "raycast", label, &world, &origins);
    }
}

fn cpu_time(c: &mut Criterion<ThreadCpu>) {
    for (label, world, origins) in worlds_and_origins() {
        scan_bench(c, "raycast_cpu", label, &world, &origins);
    }
}

/// The whole default run: corridor loop, 120 s, 6000 scans of 541 beams.
fn simulate_default(c: &mut Criterion) {
    let mut g = c.benchmark_group("simulate");
    g.sample_size(10);
    let cfg = SimConfig::default();
    let robot = RobotConfig::default();
    g.bench_function("corridor_loop_120s", |b| {
        b.iter(|| black_box(simulate(&cfg, &robot, &[], &mut |_| {}).unwrap()))
    });
    g.finish();
}

criterion_group!(raycast, wall_time, simulate_default);
criterion_group! {
    name = raycast_cpu;
    config = Criterion::default().with_measurement(ThreadCpu);
    targets = cpu_time
}
criterion_main!(raycast, raycast_cpu);
