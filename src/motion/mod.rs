//! Motion: SMPL-X pose sequences in time, the files they travel in, real mocap turned into
//! them, the motion-primitive model that makes new ones, and what is done to a sequence once
//! made. Owns frame rates and sequences of body parameters; the body itself (skinning) is
//! `body`'s.
//!
//! Files and mocap: `amass` (AMASS-style SMPL-X `.npz` written and read, SAMP-style read),
//! `bvh` (BVH reading and the source skeleton's forward kinematics), `retarget` (a CMU BVH clip
//! onto the SMPL-X body joints), `deepmimic` (DeepMimic clips retargeted onto the body),
//! `resample` (frame-rate changes and left ↔ right mirroring), `scripted` (a hand-written walk
//! cycle for demos and tests). Primitives: `primitive` (20-frame primitives in their canonical
//! frames), `cvae` (the conditional VAE that decodes them). A sequence finished: `joins` (the
//! joins of primitives smoothed), `head_stabilise` (the head held steady while the torso
//! sways), `hands` (the fingers moved with what the hands do); `activity_clip` (activity clips
//! and the pose tools that play them); `head_motion` (how a head moves, measured the same way
//! for takes and real references). Jobs of the commands that read and write motion data: `jobs`
//! (`egogen motion stats` and `hand-stats`, `egogen body pose`), `clip_import` (`egogen motion
//! import`). `mocap_tests`: BVH reading, retargeting, resampling and primitives (tests only).

pub(crate) mod activity_clip;
pub mod amass;
pub mod bvh;
pub(crate) mod clip_import;
pub mod cvae;
pub mod deepmimic;
pub mod hands;
pub mod head_motion;
pub(crate) mod head_stabilise;
pub(crate) mod jobs;
pub(crate) mod joins;
#[cfg(test)]
mod mocap_tests;
pub mod primitive;
pub(crate) mod resample;
pub(crate) mod retarget;
pub(crate) mod scripted;

pub use amass::{MotionFileError, MotionSequence};
