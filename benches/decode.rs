//! Decoding the Intel bag (13,631 scans, 26,915 odometry messages) into a
//! Recording: the whole MCAP reader (chunk decompression, CDR, sorting).

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use odocal::io::{read_mcap, read_mcap_bytes, ReadOptions};

fn data_dir() -> PathBuf {
    std::env::var_os("ODOCAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"))
}

fn decode(c: &mut Criterion) {
    let path = data_dir().join("slam-benchmark/intel.mcap");
    let Ok(bytes) = std::fs::read(&path) else {
        eprintln!(
            "SKIP decode bench: {} not found (set ODOCAL_DATA)",
            path.display()
        );
        return;
    };
    let opts = ReadOptions::default();
    let mut g = c.benchmark_group("decode");
    g.sample_size(10);
    g.bench_function("intel_mcap_in_memory", |b| {
        b.iter(|| {
            let r = read_mcap_bytes(&bytes, "intel.mcap", &opts).unwrap();
            assert_eq!(r.scans.len(), 13631);
            r
        })
    });
    g.bench_function("intel_mcap_from_file", |b| {
        b.iter(|| read_mcap(&path, &opts).unwrap())
    });
    g.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);
