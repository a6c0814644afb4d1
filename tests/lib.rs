//! Integration tests, compiled as one binary.

mod sim_effects;
mod sim_scenario;
mod sim_sensors;
mod support;
