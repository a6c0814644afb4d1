//! `odocal live` and `odocal play`: the command line's side (arguments,
//! the stop signal, what is printed). Without the `live` feature both
//! refuse with a message saying so.

use clap::Args;
use std::path::PathBuf;

use super::args::Common;

#[derive(Args)]
pub struct LiveArgs {
    /// Output directory, written when stopped (SIGINT, SIGTERM): calibration.csv,
    /// trajectory.tum, summary.json (as `calibrate`), live.json (latencies, CPU, traffic).
    #[arg(long, value_name = "DIR", default_value = "odocal-live")]
    pub out: PathBuf,
    /// Calibrator: adaptive-pf, pf, dkf, akf, none.
    #[arg(long)]
    pub method: Option<odocal::calib::Method>,
    /// Seed of every random draw.
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// The node's name.
    #[arg(long, value_name = "NAME", default_value = "odocal")]
    pub node: String,
    /// Record the run for the Rerun viewer.
    #[arg(long, value_name = "FILE.rrd", conflicts_with = "connect")]
    pub rrd: Option<PathBuf>,
    /// Stream the run live to a running Rerun viewer at this address.
    #[arg(long, value_name = "ADDR")]
    pub connect: Option<String>,
    /// Print the summary as one JSON object on stdout when stopped.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args)]
pub struct PlayArgs {
    /// Recording: ROS 2 MCAP, rosbag2 SQLite or folder (played as stored), ROS 1 bag or
    /// CARMEN log (converted to ROS 2 messages first).
    pub input: PathBuf,
    /// Speed against the recording's log times.
    #[arg(
        long,
        value_name = "X",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub rate: f64,
    /// Start again at the end (header stamps move on by the recording's length) until stopped.
    #[arg(long = "loop")]
    pub looped: bool,
    /// Seconds to wait after joining before the first message (for discovery).
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub delay: f64,
    /// Print what was played as one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[cfg(feature = "dds")]
mod on {
    use super::super::args::viewer;
    use super::*;
    use odocal::pipeline::calibrate::CalibratorChoice;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    /// A flag raised by SIGINT or SIGTERM (a second signal ends at once).
    fn stop_flag() -> anyhow::Result<Arc<AtomicBool>> {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        ctrlc::set_handler(move || {
            if flag.swap(true, Ordering::Relaxed) {
                std::process::exit(130);
            }
        })?;
        Ok(stop)
    }

    pub fn live(a: LiveArgs) -> anyhow::Result<()> {
        let stop = stop_flag()?;
        let job = odocal::pipeline::live::LiveJob {
            out: a.out.clone(),
            choice: CalibratorChoice {
                method: a.method,
                seed: a.seed,
                ..CalibratorChoice::default()
            },
            viewer: viewer(a.rrd.as_ref(), a.connect.as_ref(), false),
            common: a.common.files(),
            node: a.node.clone(),
        };
        eprintln!("odocal live: joining the domain; stop with Ctrl-C (SIGINT) or SIGTERM");
        let done = odocal::pipeline::live::run(
            &job,
            stop,
            Box::new(|m: &str| eprintln!("odocal live: {m}")),
        )?;
        let r = &done.report;
        eprintln!(
            "odocal live: {:.1} s, {} odometry and {} diagnostics published; scan → estimate \
             median {:.1} ms (p95 {:.1}); wheel → odometry median {:.2} ms; CPU {:.0} % of a \
             core",
            r.run_s,
            r.odometry_published,
            r.diagnostics_published,
            r.scan_to_estimate.median_ms,
            r.scan_to_estimate.p95_ms,
            r.wheel_to_odometry.median_ms,
            100.0 * r.cpu_share
        );
        let c = &done.calibration;
        for change in &c.summary.changes {
            eprintln!("{}", odocal::pipeline::changes::describe(change));
        }
        if a.json {
            return super::super::print_json(&c.paste.with(&c.summary));
        }
        super::super::print::calibration(&c.summary, &a.out);
        super::super::print::paste(&c.paste, &a.out);
        Ok(())
    }

    pub fn play(a: PlayArgs) -> anyhow::Result<()> {
        let stop = stop_flag()?;
        let job = odocal::pipeline::play::PlayJob {
            input: a.input.clone(),
            rate: a.rate,
            looped: a.looped,
            delay_s: a.delay,
            common: a.common.files(),
        };
        let played = odocal::pipeline::play::run(&job, &stop)?;
        if a.json {
            return super::super::print_json(&played);
        }
        eprintln!(
            "odocal play: {} messages in {:.1} s ({} round(s) of {:.1} s at ×{}); at most {:.3} s \
             behind schedule",
            played.messages,
            played.wall_s,
            played.rounds,
            played.round_s,
            a.rate,
            played.max_behind_s
        );
        Ok(())
    }
}

#[cfg(feature = "dds")]
pub use on::{live, play};

#[cfg(not(feature = "dds"))]
fn not_built() -> anyhow::Result<()> {
    Err(odocal::pipeline::PipelineError::BadArgument(
        "this odocal was built without the `live` feature (ROS 2 over DDS): build with \
         default features, or `--features live`"
            .into(),
    )
    .into())
}

#[cfg(not(feature = "dds"))]
pub fn live(_a: LiveArgs) -> anyhow::Result<()> {
    not_built()
}

#[cfg(not(feature = "dds"))]
pub fn play(_a: PlayArgs) -> anyhow::Result<()> {
    not_built()
}
