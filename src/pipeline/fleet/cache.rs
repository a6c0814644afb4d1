//! The fleet's result cache: `OUT/cache/HASH.json` holds a recording's
//! outcome with the settings it was computed under; a result computed
//! under other settings is not reused.

use super::inputs::hex;
use super::FleetJob;
use crate::fleet::Outcome;
use crate::pipeline::PipelineError;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

#[derive(Serialize, Deserialize)]
struct Cached {
    settings: String,
    outcome: Outcome,
}

fn path(out: &Path, hash: &str) -> PathBuf {
    out.join("cache").join(format!("{hash}.json"))
}

/// SHA-256 of what decides a recording's result besides its bytes:
/// odocal's version, the robot and configuration files' contents and the
/// calibrator choices.
pub fn settings_key(job: &FleetJob) -> Result<String, PipelineError> {
    let mut h = Sha256::new();
    h.update(concat!("odocal ", env!("CARGO_PKG_VERSION")).as_bytes());
    for file in [&job.common.robot, &job.common.config] {
        match file {
            // A bundled robot's name stands for its compiled-in file.
            Some(p) if !p.is_file() => {
                h.update(b"name");
                h.update(p.display().to_string().as_bytes());
            }
            Some(p) => {
                let bytes = std::fs::read(p).map_err(|e| {
                    crate::error::InputError::new(
                        p.display().to_string(),
                        format!("cannot read: {e}"),
                    )
                })?;
                h.update(b"file");
                h.update(&bytes);
            }
            None => h.update(b"none"),
        }
    }
    h.update(format!("{:?}", job.choice).as_bytes());
    Ok(hex(&h.finalize()))
}

/// The cached outcome of `hash` under `settings`, if any (an unreadable or
/// stale entry is no entry).
pub fn load(out: &Path, hash: &str, settings: &str) -> Option<Outcome> {
    let text = std::fs::read_to_string(path(out, hash)).ok()?;
    let c: Cached = serde_json::from_str(&text).ok()?;
    (c.settings == settings).then_some(c.outcome)
}

/// Stores the outcome of `hash` under `settings` (atomically).
pub fn store(
    out: &Path,
    hash: &str,
    settings: &str,
    outcome: &Outcome,
) -> Result<(), PipelineError> {
    let p = path(out, hash);
    if let Some(dir) = p.parent() {
        std::fs::create_dir_all(dir).map_err(|e| PipelineError::write(dir, e))?;
    }
    let text = serde_json::to_string_pretty(&Cached {
        settings: settings.to_string(),
        outcome: outcome.clone(),
    })
    .map_err(|e| PipelineError::write(&p, e))?;
    crate::io::atomic::write_bytes_atomic(&p, text.as_bytes())
        .map_err(|e| PipelineError::write(&p, e))
}

#[cfg(test)]
mod tests {
    /// A cached result must read back bit for bit: the trends fitted over a
    /// fleet difference near-equal radii, so a value read one ulp off
    /// changes a rate in its 12th digit and a re-run from the cache (or a
    /// Ray run, whose results also travel as JSON) no longer gives the same
    /// summary as the first run. serde_json parses exactly only with its
    /// `float_roundtrip` feature.
    #[test]
    fn cached_numbers_read_back_bit_for_bit() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut off = 0;
        for _ in 0..20_000 {
            let x: f64 = rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-8..3));
            let text = serde_json::to_string(&x).unwrap();
            let back: f64 = serde_json::from_str(&text).unwrap();
            if back.to_bits() != x.to_bits() {
                off += 1;
            }
        }
        assert_eq!(off, 0, "{off} of 20000 numbers read back changed");
    }
}
