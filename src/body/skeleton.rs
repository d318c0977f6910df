//! The SMPL-X skeleton: 55 joint names, the parent table and the pose-vector layout.

/// Number of SMPL-X joints.
pub const NUM_JOINTS: usize = 55;
/// Number of body joints driven by the motion model (pelvis + 21).
pub(crate) const NUM_BODY_JOINTS: usize = 22;
/// Length of a full SMPL-X pose vector (55 joints × axis-angle 3).
pub const POSE_DIM: usize = NUM_JOINTS * 3;

/// Joint indices used throughout egogen.
pub mod joint {
    pub(crate) const PELVIS: usize = 0;
    pub(crate) const LEFT_HIP: usize = 1;
    pub(crate) const RIGHT_HIP: usize = 2;
    pub(crate) const LEFT_KNEE: usize = 4;
    pub(crate) const RIGHT_KNEE: usize = 5;
    pub(crate) const LEFT_ANKLE: usize = 7;
    pub(crate) const RIGHT_ANKLE: usize = 8;
    pub(crate) const LEFT_FOOT: usize = 10;
    pub(crate) const RIGHT_FOOT: usize = 11;
    pub(crate) const NECK: usize = 12;
    pub(crate) const HEAD: usize = 15;
    pub(crate) const LEFT_SHOULDER: usize = 16;
    pub(crate) const RIGHT_SHOULDER: usize = 17;
    pub(crate) const LEFT_ELBOW: usize = 18;
    pub(crate) const RIGHT_ELBOW: usize = 19;
    pub(crate) const LEFT_WRIST: usize = 20;
    pub(crate) const RIGHT_WRIST: usize = 21;
    pub(crate) const LEFT_EYE: usize = 23;
    pub(crate) const RIGHT_EYE: usize = 24;
}

/// SMPL-X joint names, in index order (the names the `smplx` package uses).
pub const JOINT_NAMES: [&str; NUM_JOINTS] = [
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "jaw",
    "left_eye_smplhf",
    "right_eye_smplhf",
    "left_index1",
    "left_index2",
    "left_index3",
    "left_middle1",
    "left_middle2",
    "left_middle3",
    "left_pinky1",
    "left_pinky2",
    "left_pinky3",
    "left_ring1",
    "left_ring2",
    "left_ring3",
    "left_thumb1",
    "left_thumb2",
    "left_thumb3",
    "right_index1",
    "right_index2",
    "right_index3",
    "right_middle1",
    "right_middle2",
    "right_middle3",
    "right_pinky1",
    "right_pinky2",
    "right_pinky3",
    "right_ring1",
    "right_ring2",
    "right_ring3",
    "right_thumb1",
    "right_thumb2",
    "right_thumb3",
];

/// SMPL-X parent of each joint; the root (pelvis) has none.
pub const PARENTS: [Option<usize>; NUM_JOINTS] = {
    const P: [i32; NUM_JOINTS] = [
        -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 15, 15, 15, 20,
        25, 26, 20, 28, 29, 20, 31, 32, 20, 34, 35, 20, 37, 38, 21, 40, 41, 21, 43, 44, 21, 46, 47,
        21, 49, 50, 21, 52, 53,
    ];
    let mut out = [None; NUM_JOINTS];
    let mut i = 1;
    while i < NUM_JOINTS {
        out[i] = Some(P[i] as usize);
        i += 1;
    }
    out
};

/// Where each part of the 165-value pose vector starts (in values, not joints).
///
/// Layout: global_orient 3 | body 21×3 | jaw 3 | left eye 3 | right eye 3 | left hand 15×3 |
/// right hand 15×3 — joint `j` occupies values `3j..3j+3`. The whole layout is named, read or not.
#[allow(dead_code)]
pub(crate) mod pose_layout {
    pub(crate) const GLOBAL_ORIENT: usize = 0;
    pub(crate) const BODY: usize = 3;
    pub(crate) const JAW: usize = 66;
    pub(crate) const LEFT_EYE: usize = 69;
    pub(crate) const RIGHT_EYE: usize = 72;
    pub(crate) const LEFT_HAND: usize = 75;
    pub(crate) const RIGHT_HAND: usize = 120;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parents_precede_children() {
        for (j, p) in PARENTS.iter().enumerate() {
            if let Some(p) = p {
                assert!(*p < j, "joint {j} parent {p}");
            }
        }
        assert_eq!(JOINT_NAMES[joint::LEFT_EYE], "left_eye_smplhf");
        assert_eq!(JOINT_NAMES[joint::HEAD], "head");
    }
}
