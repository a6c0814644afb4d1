//! Integration tests, compiled as one binary.

mod support;
mod sim_scenario;
mod sim_effects;
mod sim_sensors;
