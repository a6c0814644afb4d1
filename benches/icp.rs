//! One LMS111 pair (541 beams, 270°) in a room with furniture: matcher
//! throughput in pairs per second on one core. And per benchmark log
//! (Intel, MIT-CSAIL, FR079, ACES under `$ODOCAL_DATA/slam-benchmark`, read
//! once): the time per scan pair of matching the first 1,000 scans with the
//! log's odometry as prior, as `odocal icp` does (decoding excluded), with
//! every point of the scans and with two thinned sources.

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::Point2;
use odocal::geom::{self, pose, Pose2};
use odocal::icp::match_recording;
use odocal::icp::{IcpParams, ScanMatcher};
use odocal::io::{read_mcap, ReadOptions};
use odocal::scan::LaserScan;
use odocal::sim::worlds;
use odocal::traj::Trajectory;

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

fn data_dir() -> PathBuf {
    std::env::var_os("ODOCAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"))
}

/// Scans matched per log and iteration.
const LOG_SCANS: usize = 1000;

fn logs(c: &mut Criterion) {
    let mut g = c.benchmark_group("icp_log");
    g.sample_size(10);
    for name in ["intel", "mit-csail", "fr079", "aces"] {
        let path = data_dir().join(format!("slam-benchmark/{name}.mcap"));
        let Ok(rec) = read_mcap(&path, &ReadOptions::default()) else {
            eprintln!(
                "SKIP icp bench {name}: {} not read (set ODOCAL_DATA)",
                path.display()
            );
            continue;
        };
        let scans = &rec.scans[..LOG_SCANS.min(rec.scans.len())];
        let mut odom = Trajectory::default();
        for p in &rec.odom {
            odom.push(p.stamp, p.pose);
        }
        let mount = rec.base_from_laser.unwrap_or_else(Pose2::identity);
        g.throughput(Throughput::Elements(scans.len() as u64 - 1));
        // The default, and the thinned sources of docs/performance.md's "Speed against
        // thinning": every second beam, and that with one point per 10 cm cell.
        let thinned = |beam_stride, voxel_size| IcpParams {
            beam_stride,
            voxel_size,
            ..IcpParams::default()
        };
        for (suffix, params) in [
            ("", IcpParams::default()),
            ("_every_2nd_beam", thinned(2, 0.0)),
            ("_every_2nd_beam_10cm_cells", thinned(2, 0.1)),
        ] {
            g.bench_function(format!("{name}_per_pair{suffix}"), |b| {
                b.iter(|| match_recording(scans, mount, Some(&odom), &params).unwrap())
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench, logs);
criterion_main!(benches);
