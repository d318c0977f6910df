//! Motion: SMPL-X pose sequences in time, the files they travel in, and real mocap turned
//! into them (BVH reading, retargeting, resampling, mirroring); activity clips and the pose
//! tools that play them (`activity_clip`); how a head moves, measured the same way for takes
//! and real references (`head_motion`), the joins of primitives smoothed (`joins`), the head
//! held steady while the torso sways (`head_stabilise`) and the fingers moved with what the
//! hands do (`hands`); the jobs of the commands that read and write motion data (`jobs`: `egogen
//! motion stats` and `hand-stats`, `egogen body pose`; `clip_import`: `egogen motion import`).
//!
//! Owns frame rates and sequences of body parameters; the body itself (skinning) is `body`'s.

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
pub mod primitive;
pub mod resample;
pub mod retarget;
pub mod scripted;

pub use amass::{MotionFileError, MotionSequence};
