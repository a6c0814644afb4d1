//! Integration tests, compiled as one binary.

mod diagnose_encoder_table;
mod diagnose_figures;
mod diagnose_sim;
mod diagnose_synthetic;
mod icp_bad_input;
mod icp_real;
mod icp_sim;
mod io_bad_input;
mod io_crosscheck;
mod io_read;
mod io_roundtrip;
mod sim_effects;
mod sim_scenario;
mod sim_sensors;
mod support;
