//! The body: SMPL-X skeleton, model files, skinning and the eye anchor (CPF).
//!
//! Owns the 55-joint skeleton, the rest mesh with its blend shapes and skin weights, LBS
//! exactly as `smplx` computes it, `world_from_cpf` and the hands' landmarks in MPS order.
//! Timing and sequences belong to `motion`.
//!
//! Here: `skeleton` (joint names, parent table, pose-vector layout), `model` (the model in
//! memory), `model_file` (reading a model's SMPL-X `.npz`), `lbs` (shape blend shapes, pose
//! correctives and linear blend skinning), `cpf` (the eye anchor of a posed skeleton), `markers`
//! (the surface vertices the motion loop tracks), `hand_landmarks` (the hands' landmarks in MPS
//! order), `volume` (capsules around the bones), `occupancy` (whether a point lies inside a posed
//! body), `parts` (the hands and forearms a frame's segmentation tells apart), `export` (posed
//! meshes as OBJ), `info` (`egogen body info`'s summary of a model); `properties_tests` (tests
//! only: rotations and skinning at the numerical extremes).

pub(crate) mod cpf;
pub(crate) mod export;
pub(crate) mod hand_landmarks;
pub(crate) mod info;
pub(crate) mod lbs;
pub(crate) mod markers;
pub(crate) mod model;
pub(crate) mod model_file;
pub(crate) mod occupancy;
pub(crate) mod parts;
#[cfg(test)]
mod properties_tests;
pub(crate) mod skeleton;
pub(crate) mod volume;

pub use cpf::CpfCalibration;
pub use lbs::{BodyParams, PoseError, PosedBody, PosedSkeleton, ShapedBody, CORRECTIVE_BATCH};
pub use markers::{farthest_point_markers, MarkerFrame, NUM_MARKERS};
pub use model::{BodyModel, BodyUvs};
pub use model_file::ModelFileError;
pub(crate) use occupancy::BodyOccupancy;
pub use skeleton::{joint, JOINT_NAMES, NUM_JOINTS, PARENTS, POSE_DIM};
pub(crate) use volume::CapsuleVolume;
