//! What is left in the residuals, per stream: structure tests on binned
//! normalised residuals, and summary statistics.

use super::data::{Part, GROUPS};
use super::stats::{SeriesStats, StructureTest};
use super::DiagnoseParams;
use crate::effects::Departures;
use std::collections::BTreeMap;

/// Binned normalised residuals (per bin: Σ e / (scale √n)) and bin times.
fn binned(mids: &[f64], e: &[f64], scale: f64, bin: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut t, mut z) = (Vec::new(), Vec::new());
    let Some(&t0) = mids.first() else {
        return (t, z);
    };
    let (mut k, mut s, mut n, mut ts) = (0i64, 0.0, 0usize, 0.0);
    for (m, v) in mids.iter().zip(e) {
        let kk = ((m - t0) / bin).floor() as i64;
        if kk != k && n > 0 {
            t.push(ts / n as f64);
            z.push(s / (scale * (n as f64).sqrt()));
            (s, n, ts) = (0.0, 0, 0.0);
        }
        k = kk;
        s += v;
        n += 1;
        ts += m;
    }
    if n > 0 {
        t.push(ts / n as f64);
        z.push(s / (scale * (n as f64).sqrt()));
    }
    (t, z)
}

/// Structure tests per stream (mean, trend, Ljung–Box) on the residuals of
/// `x` over `all` rows, normalised by the stream's noise `scale` and binned
/// over `p.bin_seconds`.
pub fn structure(
    all: Part,
    x: &Departures,
    scale: &[f64; 4],
    p: &DiagnoseParams,
) -> BTreeMap<String, StructureTest> {
    let mut e: [Vec<f64>; 4] = Default::default();
    all.normalised(x, &mut e);
    let mi: Vec<f64> = all.icp.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect();
    let mg: Vec<f64> = all.gyro.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect();
    let mut out = BTreeMap::new();
    for g in 0..4 {
        let mids = if g < 3 { &mi } else { &mg };
        let (t, z) = binned(mids, &e[g], scale[g], p.bin_seconds);
        if let Some(s) = StructureTest::run(&t, &z, p.ljung_box_lags) {
            out.insert(GROUPS[g].to_string(), s);
        }
    }
    out
}

/// Whether any test of any stream rejects at family-wise level `alpha`
/// (Bonferroni over three tests per stream).
pub fn has_structure(tests: &BTreeMap<String, StructureTest>, alpha: f64) -> bool {
    let m = (3 * tests.len()).max(1) as f64;
    tests.values().any(|s| s.min_p() < alpha / m)
}

/// Summary statistics of the residuals of every non-empty stream.
pub fn stream_stats(res: &[Vec<f64>; 4]) -> BTreeMap<String, SeriesStats> {
    (0..4)
        .filter(|g| !res[*g].is_empty())
        .map(|g| (GROUPS[g].to_string(), SeriesStats::of(&res[g])))
        .collect()
}
