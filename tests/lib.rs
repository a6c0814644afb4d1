//! Integration tests, compiled as one binary.

mod classic_compare;
mod classic_ga;
mod classic_heading_pf;
mod classic_seed_tables;
mod classic_umbmark;
mod sim_effects;
mod sim_scenario;
mod sim_sensors;
mod support;
