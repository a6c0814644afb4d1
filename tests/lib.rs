//! Integration tests, compiled as one binary.

mod io_crosscheck;
mod io_read;
mod support;

mod eval_evo;
mod sim_scenario;
mod eval_align;
mod eval_inputs;
mod eval_relations;
