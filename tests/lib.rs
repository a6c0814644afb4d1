//! Integration tests, compiled as one binary.

mod icp_bad_input;
mod icp_real;
mod icp_sim;
mod io_bad_input;
mod io_crosscheck;
mod io_read;
mod io_roundtrip;
mod support;
