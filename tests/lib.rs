//! Integration tests, compiled as one binary.

mod calib_censi;
mod calib_filters;
mod calib_resample;
mod classic_compare;
mod classic_ga;
mod classic_heading_pf;
mod classic_seed_tables;
mod classic_umbmark;
mod eval_align;
mod eval_evo;
mod eval_inputs;
mod eval_relations;
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
