//! BVH motion capture: reading (`bvh_anim`) and forward kinematics of the source skeleton.
//!
//! Rotation channels compose in the order they are listed (`Zrotation Yrotation Xrotation` →
//! `R = Rz · Ry · Rx`), as the BVH format defines; a joint's zero rotation is its rest pose,
//! given by the OFFSETs. Units are the file's (CMU: ≈ 0.0564 m per unit).

use std::path::{Path, PathBuf};

use bvh_anim::ChannelType;

use crate::math::{axis_angle_to_matrix, Affine3, Mat3, Vec3};

/// A channel of a joint: what it moves and where its value sits in a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    Position(usize),
    Rotation(usize),
}

/// One joint of the source skeleton.
#[derive(Debug, Clone)]
pub struct BvhJoint {
    pub name: String,
    pub parent: Option<usize>,
    /// Offset from the parent (file units).
    pub offset: Vec3,
    /// Channels in file order, each with its axis (0 = x) and its index into a frame.
    pub channels: Vec<(Channel, usize)>,
    /// End-site offset, for leaf joints.
    pub end_site: Option<Vec3>,
}

/// A BVH clip: skeleton, frame rate, channel values per frame.
#[derive(Debug, Clone)]
pub struct BvhClip {
    pub source: PathBuf,
    pub joints: Vec<BvhJoint>,
    pub frame_rate_hz: f64,
    /// Channel values (degrees for rotations) per frame.
    pub frames: Vec<Vec<f64>>,
}

/// A BVH file that could not be used.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    #[error("BVH {path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

impl BvhClip {
    /// Reads a BVH file.
    pub fn read(path: &Path) -> Result<Self, BvhError> {
        let bad = |message: String| BvhError::Invalid {
            path: path.to_owned(),
            message,
        };
        let bytes = std::fs::read(path).map_err(|e| bad(format!("cannot read ({e})")))?;
        let bvh = crate::parser_guard::catch_parser_panic(|| bvh_anim::from_bytes(&bytes))
            .map_err(|e| bad(format!("not a valid BVH file ({e})")))?
            .map_err(|e| bad(format!("not a valid BVH file ({e})")))?;
        let joints: Vec<BvhJoint> = bvh
            .joints()
            .map(|j| {
                let d = j.data();
                let v = |o: &mint::Vector3<f32>| Vec3::new(o.x as f64, o.y as f64, o.z as f64);
                BvhJoint {
                    name: d.name().to_string(),
                    parent: d.parent_index(),
                    offset: v(d.offset()),
                    channels: d
                        .channels()
                        .iter()
                        .map(|c| {
                            let kind = match c.channel_type() {
                                ChannelType::PositionX => Channel::Position(0),
                                ChannelType::PositionY => Channel::Position(1),
                                ChannelType::PositionZ => Channel::Position(2),
                                ChannelType::RotationX => Channel::Rotation(0),
                                ChannelType::RotationY => Channel::Rotation(1),
                                ChannelType::RotationZ => Channel::Rotation(2),
                            };
                            (kind, c.motion_index())
                        })
                        .collect(),
                    end_site: d.end_site().map(v),
                }
            })
            .collect();
        if joints.is_empty() {
            return Err(bad("no joints in HIERARCHY".into()));
        }
        let frame_time_s = bvh.frame_time().as_secs_f64();
        if !(frame_time_s > 0.0) {
            return Err(bad(format!(
                "Frame Time must be positive, found {frame_time_s}"
            )));
        }
        // "Frame Time: .0083333" means 120 Hz: snap rates within 0.1 % of an integer.
        let rate = 1.0 / frame_time_s;
        let frame_rate_hz = if (rate - rate.round()).abs() < 1e-3 * rate {
            rate.round()
        } else {
            rate
        };
        let frames: Vec<Vec<f64>> = bvh
            .frames()
            .map(|f| f.as_slice().iter().map(|&x| x as f64).collect())
            .collect();
        if frames.is_empty() {
            return Err(bad("no frames in MOTION".into()));
        }
        if let Some((i, _)) = frames
            .iter()
            .enumerate()
            .find(|(_, f)| f.iter().any(|x| !x.is_finite()))
        {
            return Err(bad(format!("frame {i} holds a non-finite value")));
        }
        Ok(Self {
            source: path.to_owned(),
            joints,
            frame_rate_hz,
            frames,
        })
    }

    /// Index of the joint called `name`.
    pub(crate) fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// `world_from_joint` of every joint at frame `f` (file units and axes).
    pub(crate) fn global_transforms(&self, f: usize) -> Vec<Affine3> {
        let values = &self.frames[f];
        let mut out: Vec<Affine3> = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            let mut rot = Mat3::IDENTITY;
            let mut pos = j.offset;
            for &(kind, idx) in &j.channels {
                match kind {
                    Channel::Position(a) => pos[a] = j.offset[a] + values[idx],
                    Channel::Rotation(a) => {
                        rot *= axis_angle_to_matrix(Vec3::AXES[a] * values[idx].to_radians())
                    }
                }
            }
            let local = Affine3 {
                matrix3: rot,
                translation: pos,
            };
            out.push(match j.parent {
                Some(p) => out[p] * local,
                None => local,
            });
        }
        out
    }

    /// Rest-pose joint positions (all rotations zero, root at its offset).
    pub(crate) fn rest_positions(&self) -> Vec<Vec3> {
        let mut out: Vec<Vec3> = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            out.push(j.parent.map_or(j.offset, |p| out[p] + j.offset));
        }
        out
    }
}
