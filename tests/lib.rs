//! Integration tests, compiled as one binary.

mod support;
mod diagnose_synthetic;
