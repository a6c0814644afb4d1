//! Integration tests, compiled as one binary.

mod support;
mod viz_logger;
mod viz_plot;
mod viz_report;
mod viz_rrd;
