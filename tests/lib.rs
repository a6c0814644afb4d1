//! Integration tests, compiled as one binary.

mod diagnose_encoder_table;
mod diagnose_figures;
mod diagnose_synthetic;
mod sim_effects;
mod sim_scenario;
mod sim_sensors;
mod support;
