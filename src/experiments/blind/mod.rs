//! `odocal experiment diagnose`: the blind diagnosis suite. Every case of
//! [`cases::cases`] (nothing hidden, each effect of the table, pairs,
//! triples, faults outside the table) is simulated over `--runs` seeds, the
//! scenarios taken in turn, written as a bag, read back, matched by ICP and
//! diagnosed with the nominal robot; the table gives per case how often the
//! hidden causes were named right, how often a cause was named that was not
//! hidden, how often one was missed, and whether the estimates held.

pub mod cases;
mod run;
mod table;

pub use cases::{cases, Case, Group};
pub use run::{estimate_misses, run_case, score, BlindRun};
pub use table::{summarise, BlindRow, BlindSummary};

use super::inputs::{bad, ExperimentInputs};
use super::output::{draw_bars, ExperimentOutput};
use crate::pipeline::PipelineError;
use crate::viz::plot::BarChart;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Settings of the blind suite (`[diagnose]` of `--settings`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlindParams {
    /// Scenarios, taken in turn by seed (run k of a case drives scenario
    /// k mod len).
    pub scenarios: Vec<String>,
    /// Length of each run (s).
    pub duration_s: f64,
    /// Laser rate (Hz); 25 Hz as the bundled recording.
    pub laser_rate_hz: f64,
    /// Case families to run (`null`, `single`, `pair`, `triple`, `fault`).
    pub groups: Vec<String>,
    /// Only the cases whose label contains one of these (all when empty).
    pub only: Vec<String>,
}

impl Default for BlindParams {
    fn default() -> Self {
        Self {
            scenarios: crate::sim::BUILTIN_SCENARIOS
                .iter()
                .map(|s| s.to_string())
                .collect(),
            duration_s: 90.0,
            laser_rate_hz: 25.0,
            groups: Group::ALL.iter().map(|g| g.name().to_string()).collect(),
            only: Vec::new(),
        }
    }
}

impl BlindParams {
    /// The cases these settings select.
    pub fn selected(&self) -> Result<Vec<Case>, PipelineError> {
        for g in &self.groups {
            if !Group::ALL.iter().any(|x| x.name() == g) {
                return Err(bad(format!(
                    "diagnose.groups: unknown group '{g}' (known: null, single, pair, triple, fault)"
                )));
            }
        }
        if self.scenarios.is_empty() || !(self.duration_s >= 20.0) {
            return Err(bad("diagnose: at least one scenario and duration_s ≥ 20 s"));
        }
        Ok(cases(self.duration_s)
            .into_iter()
            .filter(|c| self.groups.iter().any(|g| g == c.group.name()))
            .filter(|c| self.only.is_empty() || self.only.iter().any(|o| c.label.contains(o)))
            .collect())
    }
}

/// Runs every selected case over `runs` seeds from `seed`; progress on stderr.
pub fn blind_suite(
    inp: &ExperimentInputs<'_>,
    p: &BlindParams,
    dir: &Path,
) -> Result<BlindSummary, PipelineError> {
    let cases = p.selected()?;
    std::fs::create_dir_all(dir).map_err(|e| PipelineError::write(dir, e))?;
    let mut runs = Vec::new();
    for case in &cases {
        for k in 0..inp.runs {
            let seed = inp.seed + k as u64;
            let scenario = &p.scenarios[k % p.scenarios.len()];
            let r = run_case(case, scenario, seed, p, inp, dir)?;
            eprintln!(
                "{} | {scenario} seed {seed}: {} {:?}{}",
                case.label,
                r.verdict,
                r.named,
                if r.right { "" } else { "  ✗" }
            );
            runs.push(r);
        }
    }
    Ok(summarise(&cases, runs, p))
}

/// `odocal experiment diagnose`: the suite, its table and a bar chart of
/// the rates per case.
pub(crate) fn blind_output(
    inp: &ExperimentInputs<'_>,
    p: &BlindParams,
    out: &Path,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let s = blind_suite(inp, p, &out.join("blind-bags"))?;
    let _ = std::fs::remove_dir(out.join("blind-bags"));
    let labels: Vec<String> = s.rows.iter().map(|r| r.case.clone()).collect();
    let chart = BarChart::new(
        format!(
            "Blind diagnosis through simulator, bag and ICP ({} seeds per case)",
            inp.runs
        ),
        labels,
        vec!["named right".into(), "false cause".into(), "missed".into()],
    )
    .panel(
        "share of runs (%)",
        vec![
            s.rows.iter().map(|r| r.right_pct).collect(),
            s.rows.iter().map(|r| r.false_pct).collect(),
            s.rows.iter().map(|r| r.missed_pct).collect(),
        ],
        None,
    );
    draw_bars(png, &chart)?;
    Ok(ExperimentOutput::titled(
        "Blind diagnosis suite",
        s.markdown(),
        &s,
    ))
}
