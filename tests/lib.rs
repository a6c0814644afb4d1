//! Integration tests, compiled as one binary.

mod support;
mod sim_scenario;
