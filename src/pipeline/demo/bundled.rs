//! The recording `odocal demo` runs on by default, and its simulator truth,
//! compiled into the binary (4.3 MB and 1 MB) so that an installed or moved
//! `odocal` runs the demo without the repository: nothing is read from
//! `scans/` at run time, and nothing is copied into the output directory.

/// The bundled recording's name in reports (no path: it is read from memory).
pub const RECORDING_NAME: &str = "wheelchair-corridor.mcap (bundled)";

/// `scans/wheelchair-corridor.mcap` (see `scans/README.md`).
pub static RECORDING: &[u8] = include_bytes!("../../../scans/wheelchair-corridor.mcap");

/// `scans/wheelchair-corridor.truth.json`: the simulator's truth for it.
pub static TRUTH: &str = include_str!("../../../scans/wheelchair-corridor.truth.json");
