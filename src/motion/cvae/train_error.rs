//! Why a training run (the primitive model's or the policy's) stopped: one error type, apart
//! from the training loop so that checkpoints (which the loop writes) do not import the loop.

use std::path::PathBuf;

/// Why training stopped.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    #[error(transparent)]
    Model(#[from] crate::body::ModelFileError),
    #[error(transparent)]
    Motion(#[from] crate::motion::MotionFileError),
    #[error(transparent)]
    Primitive(#[from] crate::motion::primitive::PrimitiveError),
    #[error(transparent)]
    Pose(#[from] crate::body::PoseError),
    #[error(transparent)]
    Weights(#[from] super::weights::WeightsError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{0}")]
    Data(String),
    #[error("training diverged: loss is {loss} at {phase} step {step}")]
    Diverged {
        phase: &'static str,
        step: usize,
        loss: f64,
    },
}
