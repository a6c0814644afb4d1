//! Integration tests, compiled as one binary.

mod support;
mod diagnose_synthetic;
mod diagnose_encoder_table;
mod diagnose_figures;
