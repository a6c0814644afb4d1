//! Integration tests, compiled as one binary.

mod classic_seed_tables;
mod classic_umbmark;
mod support;
