//! The body as tensors: 6D rotations → rotation matrices → forward kinematics of the 22 body
//! joints → the 67 markers by linear blend skinning, differentiable, batched.
//!
//! The rig is frozen from one shaped body (f64 body code): rest joints, marker rest positions and
//! their skin weights. Markers are skinned exactly as `body::lbs` does for a model without pose
//! correctives: a marker weighted to a joint outside the 22 (hands, jaw, eyes, which the motion
//! model keeps at rest) moves rigidly with that joint's nearest body ancestor, so its weight is
//! folded onto that ancestor without changing the result.

use burn::prelude::*;

use crate::body::{joint, BodyModel, PoseError, PARENTS};
use crate::math::Vec3;

/// Joints the motion model drives: pelvis (global orient) and the 21 body joints.
pub(crate) const BODY_JOINTS: usize = 22;

/// Joints whose markers count as foot markers (ankles and feet).
const FOOT_JOINTS: [usize; 4] = [
    joint::LEFT_ANKLE,
    joint::RIGHT_ANKLE,
    joint::LEFT_FOOT,
    joint::RIGHT_FOOT,
];

/// Rest geometry of one shaped body, in f64, from which tensor rigs are built.
#[derive(Debug, Clone)]
pub struct RigGeometry {
    /// Rest joints 0..22 (metres, SMPL-X body frame).
    pub rest_joints: [Vec3; BODY_JOINTS],
    /// Vertex ids of the markers (farthest-point sampling, `body::markers`).
    pub marker_ids: Vec<u32>,
    /// Rest marker positions.
    pub marker_rest: Vec<Vec3>,
    /// Skin weights of each marker over the 22 body joints (rows sum to 1).
    pub marker_weights: Vec<[f64; BODY_JOINTS]>,
    /// Markers whose largest weight is on an ankle or foot joint.
    pub foot_markers: Vec<usize>,
}

impl RigGeometry {
    /// The rig of `model` shaped by `betas`.
    pub fn new(model: &BodyModel, betas: &[f64]) -> Result<Self, PoseError> {
        let shaped = model.shape(betas, &[])?;
        let marker_ids = model.marker_ids().to_vec();
        let body_ancestor = |mut j: usize| {
            while j >= BODY_JOINTS {
                j = PARENTS[j].unwrap_or(0);
            }
            j
        };
        let marker_weights: Vec<[f64; BODY_JOINTS]> = marker_ids
            .iter()
            .map(|&v| {
                let mut w = [0.0; BODY_JOINTS];
                for &(j, wj) in &model.skin_weights[v as usize] {
                    w[body_ancestor(j as usize)] += wj;
                }
                let total: f64 = w.iter().sum();
                w.map(|x| x / total)
            })
            .collect();
        let foot_markers = marker_weights
            .iter()
            .enumerate()
            .filter(|(_, w)| {
                let dominant = (0..BODY_JOINTS)
                    .max_by(|&a, &b| w[a].total_cmp(&w[b]))
                    .unwrap_or(0);
                FOOT_JOINTS.contains(&dominant)
            })
            .map(|(m, _)| m)
            .collect();
        Ok(Self {
            rest_joints: std::array::from_fn(|j| shaped.rest_joints[j]),
            marker_rest: marker_ids
                .iter()
                .map(|&v| shaped.v_shaped[v as usize])
                .collect(),
            marker_ids,
            marker_weights,
            foot_markers,
        })
    }
}

/// The rig as constant tensors on a device.
#[derive(Debug, Clone)]
pub struct TensorRig<B: Backend> {
    /// Rest pelvis `[3]`.
    pelvis_rest: Tensor<B, 1>,
    /// Rest bone offsets `joint − parent` (index 0 unused), as rows `[22, 3]`, kept per joint.
    bone_offsets: Vec<Tensor<B, 3>>,
    /// `marker − rest joint` for every joint, `[1, 22, 3, M]`.
    marker_offsets: Tensor<B, 4>,
    /// Marker weights `[1, 22, 1, M]` and `[22, M]`.
    weights_4: Tensor<B, 4>,
    weights_2: Tensor<B, 2>,
    /// Foot marker indices.
    pub foot_markers: Tensor<B, 1, Int>,
    pub num_markers: usize,
}

impl<B: Backend> TensorRig<B> {
    pub fn new(geo: &RigGeometry, device: &B::Device) -> Self {
        let m = geo.marker_rest.len();
        let j0 = geo.rest_joints[0];
        let pelvis_rest = Tensor::from_data(
            TensorData::new(vec![j0.x as f32, j0.y as f32, j0.z as f32], [3]),
            device,
        );
        let bone_offsets = (0..BODY_JOINTS)
            .map(|j| {
                let d = match PARENTS[j] {
                    Some(p) => geo.rest_joints[j] - geo.rest_joints[p],
                    None => Vec3::ZERO,
                };
                Tensor::from_data(
                    TensorData::new(vec![d.x as f32, d.y as f32, d.z as f32], [1, 3, 1]),
                    device,
                )
            })
            .collect();
        let mut offsets = vec![0f32; BODY_JOINTS * 3 * m];
        let mut weights = vec![0f32; BODY_JOINTS * m];
        for j in 0..BODY_JOINTS {
            for (k, (p, w)) in geo.marker_rest.iter().zip(&geo.marker_weights).enumerate() {
                let o = *p - geo.rest_joints[j];
                for c in 0..3 {
                    offsets[(j * 3 + c) * m + k] = o[c] as f32;
                }
                weights[j * m + k] = w[j] as f32;
            }
        }
        let weights_2: Tensor<B, 2> =
            Tensor::from_data(TensorData::new(weights, [BODY_JOINTS, m]), device);
        let foot: Vec<i64> = geo.foot_markers.iter().map(|&i| i as i64).collect();
        Self {
            pelvis_rest,
            bone_offsets,
            marker_offsets: Tensor::from_data(
                TensorData::new(offsets, [1, BODY_JOINTS, 3, m]),
                device,
            ),
            weights_4: weights_2.clone().reshape([1, BODY_JOINTS, 1, m]),
            weights_2,
            foot_markers: Tensor::from_data(TensorData::new(foot.clone(), [foot.len()]), device),
            num_markers: m,
        }
    }

    /// Rest pelvis `[3]`.
    pub(crate) fn rest_pelvis(&self) -> Tensor<B, 1> {
        self.pelvis_rest.clone()
    }

    /// Posed joints `[N, 22, 3]`, world rotations `[N, 22, 3, 3]` and markers `[N, M, 3]` of
    /// `N` frames given local rotations `[N, 22, 3, 3]` and translations `[N, 3]` (smplx
    /// `transl`: the pelvis sits at rest pelvis + transl).
    pub(crate) fn pose(
        &self,
        local: Tensor<B, 4>,
        transl: Tensor<B, 2>,
    ) -> (Tensor<B, 3>, Tensor<B, 4>, Tensor<B, 3>) {
        let [n, _, _, _] = local.dims();
        let root_pos: Tensor<B, 3> =
            (transl + self.pelvis_rest.clone().unsqueeze_dim::<2>(0)).unsqueeze_dim(2);
        let mut rots: Vec<Tensor<B, 3>> = Vec::with_capacity(BODY_JOINTS);
        let mut pos: Vec<Tensor<B, 3>> = Vec::with_capacity(BODY_JOINTS);
        for j in 0..BODY_JOINTS {
            let r_local = local.clone().narrow(1, j, 1).reshape([n, 3, 3]);
            match PARENTS[j] {
                None => {
                    rots.push(r_local);
                    pos.push(root_pos.clone());
                }
                Some(p) => {
                    let parent = rots[p].clone();
                    let offset = parent.clone().matmul(self.bone_offsets[j].clone());
                    pos.push(pos[p].clone() + offset);
                    rots.push(parent.matmul(r_local));
                }
            }
        }
        let world_rot: Tensor<B, 4> = Tensor::stack(rots, 1);
        let joints: Tensor<B, 3> = Tensor::stack::<4>(pos, 1).reshape([n, BODY_JOINTS, 3]);
        // Marker k = Σ_j w_jk (R_j (p_k − J_j) + joint_j).
        let rotated = world_rot
            .clone()
            .matmul(self.marker_offsets.clone())
            .mul(self.weights_4.clone())
            .sum_dim(1)
            .reshape([n, 3, self.num_markers]);
        let blended = joints
            .clone()
            .swap_dims(1, 2)
            .matmul(self.weights_2.clone().unsqueeze_dim(0));
        let markers = (rotated + blended).swap_dims(1, 2);
        (joints, world_rot, markers)
    }
}

/// Rotation matrices `[..., 3, 3]` (columns b1 b2 b3) from 6D vectors `[..., 6]` by
/// Gram-Schmidt (the convention of `math::rot6d_to_matrix`).
pub(crate) fn rot6d_to_matrix<B: Backend, const D: usize, const D2: usize>(
    d6: Tensor<B, D>,
) -> Tensor<B, D2> {
    let last = D - 1;
    let a1 = d6.clone().narrow(last, 0, 3);
    let a2 = d6.narrow(last, 3, 3);
    let b1 = normalize(a1);
    let dot = (b1.clone() * a2.clone()).sum_dim(last);
    let b2 = normalize(a2 - b1.clone() * dot);
    let b3 = b1.clone().cross(b2.clone(), last);
    Tensor::stack(vec![b1, b2, b3], D)
}

/// The 6D vector `[..., 6]` (first two columns) of rotation matrices `[..., 3, 3]`.
pub(crate) fn matrix_to_rot6d<B: Backend, const D: usize, const D2: usize>(
    m: Tensor<B, D>,
) -> Tensor<B, D2> {
    let c1 = m.clone().narrow(D - 1, 0, 1);
    let c2 = m.narrow(D - 1, 1, 1);
    Tensor::cat(vec![c1, c2], D - 1)
        .swap_dims(D - 1, D - 2)
        .flatten(D - 2, D - 1)
}

fn normalize<B: Backend, const D: usize>(v: Tensor<B, D>) -> Tensor<B, D> {
    let norm = v.clone().square().sum_dim(D - 1).add_scalar(1e-8).sqrt();
    v / norm
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::POSE_DIM;
    use crate::math::{axis_angle_to_matrix, matrix_to_rot6d as rot6d_f64};
    use burn::backend::Flex;

    fn default_model() -> BodyModel {
        BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap()
    }

    #[test]
    fn tensor_markers_match_f64_skinning() {
        let model = default_model();
        let geo = RigGeometry::new(&model, &[]).unwrap();
        assert!(
            geo.foot_markers.len() >= 2,
            "foot markers: {:?}",
            geo.foot_markers
        );
        let device = Default::default();
        let rig = TensorRig::<Flex>::new(&geo, &device);
        // A deterministic, clearly non-trivial pose of the 22 body joints.
        let mut pose = [0.0; POSE_DIM];
        for (i, v) in pose.iter_mut().take(3 * BODY_JOINTS).enumerate() {
            *v = 0.6 * ((i as f64 * 1.37).sin());
        }
        let transl = Vec3::new(0.3, -0.2, 0.9);
        let shaped = model.shape(&[], &[]).unwrap();
        let expected = shaped.marker_frame(&pose, transl, &geo.marker_ids).unwrap();
        let d6: Vec<f32> = (0..BODY_JOINTS)
            .flat_map(|j| {
                let aa = Vec3::new(pose[3 * j], pose[3 * j + 1], pose[3 * j + 2]);
                rot6d_f64(axis_angle_to_matrix(aa)).map(|x| x as f32)
            })
            .collect();
        let local: Tensor<Flex, 4> = rot6d_to_matrix(Tensor::<Flex, 3>::from_data(
            TensorData::new(d6, [1, BODY_JOINTS, 6]),
            &device,
        ));
        let t = Tensor::from_data(
            TensorData::new(
                vec![transl.x as f32, transl.y as f32, transl.z as f32],
                [1, 3],
            ),
            &device,
        );
        let (joints, _, markers) = rig.pose(local, t);
        let joints: Vec<f32> = joints.into_data().to_vec().unwrap();
        let markers: Vec<f32> = markers.into_data().to_vec().unwrap();
        let mut worst: f64 = 0.0;
        for (j, e) in expected
            .skeleton
            .joints
            .iter()
            .take(BODY_JOINTS)
            .enumerate()
        {
            for c in 0..3 {
                worst = worst.max((joints[3 * j + c] as f64 - e[c]).abs());
            }
        }
        for (k, e) in expected.markers.iter().enumerate() {
            for c in 0..3 {
                worst = worst.max((markers[3 * k + c] as f64 - e[c]).abs());
            }
        }
        assert!(worst < 1e-5, "largest difference {worst} m");
    }
}
