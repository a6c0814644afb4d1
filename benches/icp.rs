//! One LMS111 pair (541 beams, 270°) in a room with furniture: matcher
//! throughput in pairs per second on one core.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Point2;
use odocal::geom::{self, pose, Pose2};
use odocal::icp::{IcpParams, ScanMatcher};
use odocal::scan::LaserScan;
use odocal::sim::worlds;

fn scan(world: &odocal::sim::World, p: Pose2, stamp: f64) -> LaserScan {
    let mut buf = vec![0.0; 541];
    let o = Point2::new(p.translation.x, p.translation.y);
    let amin = -135f64.to_radians();
    world.cast_fan(
        o,
        geom::heading(&p) + amin,
        0.5f64.to_radians(),
        20.0,
        &mut buf,
    );
    LaserScan {
        stamp,
        angle_min: amin,
        angle_increment: 0.5f64.to_radians(),
        range_min: 0.5,
        range_max: 20.0,
        ranges: buf.iter().map(|&r| r as f32).collect(),
        ..Default::default()
    }
}

fn bench(c: &mut Criterion) {
    let world = worlds::builtin("corridor-loop").unwrap();
    let a = scan(&world, pose(8.0, 1.25, 0.0), 0.0);
    let b = scan(&world, pose(8.04, 1.252, 0.004), 0.04);
    let prior = Some(pose(0.038, 0.0, 0.0035));
    let mut m = ScanMatcher::new(IcpParams::default(), Pose2::identity()).unwrap();
    m.push(&a, None);
    let mut flip = false;
    let mut t = 0.04;
    c.bench_function("icp_pair_541_beams", |bch| {
        bch.iter(|| {
            // Alternate the two scans so every call matches a fresh pair
            // (reference tree rebuilt once per pair, as in a real run).
            flip = !flip;
            t += 0.04;
            let mut s = if flip { b.clone() } else { a.clone() };
            s.stamp = t;
            let p = if flip {
                prior
            } else {
                prior.map(|p| p.inverse())
            };
            std::hint::black_box(m.push(&s, p))
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
