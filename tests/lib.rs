//! Integration tests, compiled as one binary.

mod icp_sim;
mod support;
