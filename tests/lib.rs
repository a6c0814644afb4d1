//! Integration tests, compiled as one binary.

mod calib_censi;
mod calib_filters;
mod calib_resample;
mod support;
