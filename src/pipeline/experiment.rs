//! `odocal experiment NAME`: the experiments module's driver, under the
//! pipeline's name for the command.

pub use crate::experiments::{
    run, ExperimentInputs, ExperimentOutput, ExperimentSettings, EXPERIMENTS,
};
