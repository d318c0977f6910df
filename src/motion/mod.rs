//! Motion: SMPL-X pose sequences in time, and the files they travel in.
//!
//! Owns frame rates and sequences of body parameters; the body itself (skinning) is `body`'s.

pub mod amass;
pub mod scripted;

pub use amass::{MotionFileError, MotionSequence};
