//! The blind suite's table: per case the share of runs named right, with a
//! false cause, with a hidden cause missed, with estimates in tolerance and
//! with a positive held-out gain; and the null runs' rate of
//! `no-discrepancy` with its 95 % Wilson interval.

use super::cases::{Case, Group};
use super::run::BlindRun;
use super::BlindParams;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write;

/// One case over its runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlindRow {
    /// Case label.
    pub case: String,
    /// Family.
    pub group: Group,
    /// Runs.
    pub runs: usize,
    /// Named right (%).
    pub right_pct: f64,
    /// Runs naming a cause that was not hidden (%).
    pub false_pct: f64,
    /// Runs missing a hidden cause (%).
    pub missed_pct: f64,
    /// Runs whose rightly named effects have every estimate in tolerance,
    /// over the runs that named one (%; NaN when none did).
    pub estimates_pct: f64,
    /// Runs with a positive held-out gain (%).
    pub gain_pct: f64,
    /// Verdicts and how often.
    pub verdicts: BTreeMap<String, usize>,
    /// Names given that were not hidden, and how often.
    pub false_names: BTreeMap<String, usize>,
}

/// The whole suite.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlindSummary {
    /// Settings it ran with.
    pub settings: BlindParams,
    /// One row per case.
    pub rows: Vec<BlindRow>,
    /// Null runs called `no-discrepancy`, of all null runs.
    pub null_no_discrepancy: (usize, usize),
    /// 95 % Wilson interval of that rate.
    pub null_rate_ci: (f64, f64),
    /// Every run.
    pub runs: Vec<BlindRun>,
}

fn pct(k: usize, n: usize) -> f64 {
    if n == 0 {
        f64::NAN
    } else {
        100.0 * k as f64 / n as f64
    }
}

/// 95 % Wilson score interval \[Wilson1927\] of k successes in n trials.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (z, nf) = (1.959964_f64, n as f64);
    let p = k as f64 / nf;
    let d = 1.0 + z * z / nf;
    let c = (p + z * z / (2.0 * nf)) / d;
    let h = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / d;
    ((c - h).max(0.0), (c + h).min(1.0))
}

fn row(case: &Case, runs: &[&BlindRun]) -> BlindRow {
    let n = runs.len();
    let count = |f: &dyn Fn(&BlindRun) -> bool| runs.iter().filter(|r| f(r)).count();
    let named = runs.iter().filter(|r| r.estimates_ok.is_some()).count();
    let mut verdicts = BTreeMap::new();
    let mut false_names = BTreeMap::new();
    for r in runs {
        *verdicts.entry(r.verdict.clone()).or_insert(0) += 1;
        for f in &r.false_causes {
            *false_names.entry(f.clone()).or_insert(0) += 1;
        }
    }
    BlindRow {
        case: case.label.clone(),
        group: case.group,
        runs: n,
        right_pct: pct(count(&|r| r.right), n),
        false_pct: pct(count(&|r| !r.false_causes.is_empty()), n),
        missed_pct: pct(count(&|r| !r.missed.is_empty()), n),
        estimates_pct: pct(count(&|r| r.estimates_ok == Some(true)), named),
        gain_pct: pct(count(&|r| r.gain > 0.0), n),
        verdicts,
        false_names,
    }
}

/// Rows per case and the null rate.
pub fn summarise(cases: &[Case], runs: Vec<BlindRun>, p: &BlindParams) -> BlindSummary {
    let rows: Vec<BlindRow> = cases
        .iter()
        .map(|c| {
            let rs: Vec<&BlindRun> = runs.iter().filter(|r| r.case == c.label).collect();
            row(c, &rs)
        })
        .collect();
    let nulls: Vec<&BlindRun> = runs.iter().filter(|r| r.group == Group::Null).collect();
    let k = nulls.iter().filter(|r| r.right).count();
    BlindSummary {
        settings: p.clone(),
        rows,
        null_no_discrepancy: (k, nulls.len()),
        null_rate_ci: wilson(k, nulls.len()),
        runs,
    }
}

fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.0}")
    } else {
        "–".into()
    }
}

impl BlindSummary {
    /// The table (markdown) with the settings and the null rate.
    pub fn markdown(&self) -> String {
        let s = &self.settings;
        let mut md = String::new();
        let _ = writeln!(
            md,
            "Each run: `simulate` ({} s, laser {} Hz, scenarios {} in turn by seed) → bag → \
             read back → ICP → `diagnose` with the nominal wheelchair; the truth never reaches \
             the diagnosis. Estimates in tolerance: within 20 % of the true value (of the \
             effect's largest value in that unit where the true value is zero), never widened \
             by the fit's standard error; a radius step's time within 2 s; a parameter not \
             reported is out of tolerance.\n",
            s.duration_s,
            s.laser_rate_hz,
            s.scenarios.join(", ")
        );
        let (k, n) = self.null_no_discrepancy;
        if n > 0 {
            let (lo, hi) = self.null_rate_ci;
            let _ = writeln!(
                md,
                "Null runs called `no-discrepancy`: {k} of {n} ({:.0} %, 95 % interval {:.0}–{:.0} %).\n",
                pct(k, n),
                100.0 * lo,
                100.0 * hi
            );
        }
        md.push_str(
            "| case | group | runs | named right % | false cause % | missed % | estimates ok % | gain > 0 % | verdicts | false names |\n\
             |---|---|---|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            let join = |m: &BTreeMap<String, usize>| {
                m.iter()
                    .map(|(k, v)| format!("{k} {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                r.case,
                r.group.name(),
                r.runs,
                cell(r.right_pct),
                cell(r.false_pct),
                cell(r.missed_pct),
                cell(r.estimates_pct),
                cell(r.gain_pct),
                join(&r.verdicts),
                join(&r.false_names)
            );
        }
        md
    }
}

#[cfg(test)]
mod tests {
    use super::wilson;

    #[test]
    fn wilson_interval_matches_published_values() {
        // [Wilson1927] interval for 19 of 20: 0.764–0.991 ([Newcombe1998], Table I style).
        let (lo, hi) = wilson(19, 20);
        assert!(
            (lo - 0.7639).abs() < 1e-3 && (hi - 0.9911).abs() < 1e-3,
            "{lo} {hi}"
        );
        let (lo, hi) = wilson(0, 10);
        assert!(lo == 0.0 && (hi - 0.2775).abs() < 1e-3, "{hi}");
    }
}
