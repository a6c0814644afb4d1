//! Integration tests, compiled as one binary.

mod support;

mod eval_evo;
mod sim_scenario;
