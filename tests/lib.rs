//! Integration tests, compiled as one binary.

mod io_crosscheck;
mod io_read;
mod support;

mod eval_align;
mod eval_evo;
mod eval_inputs;
mod eval_relations;
mod sim_scenario;
