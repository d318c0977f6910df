//! Skinning: shape blend shapes, joint regression, pose correctives and linear blend
//! skinning — the algorithm of `smplx/lbs.py`, in `f64`, with a joints-only fast path.
//!
//! Steps for one body (as in `smplx.lbs`):
//! 1. `v_shaped = v_template + Σ betas·shape_dirs + Σ expression·expression_dirs`
//! 2. `J = J_regressor · v_shaped` (rest joints follow shape)
//! 3. `R_j = rodrigues(pose_j)`; pose correctives `v_posed = v_shaped + posedirs · vec(R_j − I)`
//!    — skipped when the model's correctives are all zero (our default model)
//! 4. rigid chain `world_from_joint_j = world_from_joint_parent · [R_j | J_j − J_parent]`
//! 5. `v = Σ_j w_vj · world_from_joint_j · (v_posed − J_j) + transl`

use rayon::prelude::*;

use super::model::{BodyModel, POSE_FEATURES};
use super::skeleton::{NUM_JOINTS, PARENTS, POSE_DIM};
use crate::math::rotation::axis_angles_to_matrices;
use crate::math::{axis_angle_to_matrix, Affine3, Mat3, Real, Vec3};

/// Parameters of one posed body, in the `smplx` convention.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyParams {
    /// Shape coefficients; fewer than the model has are padded with zeros.
    pub betas: Vec<Real>,
    /// Expression coefficients; fewer than the model has are padded with zeros.
    pub expression: Vec<Real>,
    /// Full pose, 55 joints × axis-angle (see `skeleton::pose_layout`).
    pub pose: [Real; POSE_DIM],
    /// Translation added after posing (metres).
    pub transl: Vec3,
}

impl Default for BodyParams {
    fn default() -> Self {
        Self {
            betas: Vec::new(),
            expression: Vec::new(),
            pose: [0.0; POSE_DIM],
            transl: Vec3::ZERO,
        }
    }
}

impl BodyParams {
    /// Axis-angle of joint `j`.
    pub(crate) fn joint_axis_angle(&self, j: usize) -> Vec3 {
        Vec3::new(self.pose[3 * j], self.pose[3 * j + 1], self.pose[3 * j + 2])
    }
    /// Sets the axis-angle of joint `j`.
    pub fn set_joint_axis_angle(&mut self, j: usize, aa: Vec3) {
        self.pose[3 * j..3 * j + 3].copy_from_slice(&aa.to_array());
    }

    /// The same body moved rigidly by `new_from_old`, expressed as SMPL-X parameters.
    ///
    /// LBS rotates about the rest pelvis `rest_pelvis` (which depends on betas), so the
    /// translation is re-rooted: `transl' = R (transl + J0) − J0 + t` and
    /// `global_orient' = R · global_orient`.
    pub(crate) fn moved_rigidly(&self, new_from_old: Affine3, rest_pelvis: Vec3) -> BodyParams {
        let r = new_from_old.matrix3;
        let orient = r * axis_angle_to_matrix(self.joint_axis_angle(0));
        let mut out = self.clone();
        out.set_joint_axis_angle(0, crate::math::matrix_to_axis_angle(orient));
        out.transl = r * (self.transl + rest_pelvis) - rest_pelvis + new_from_old.translation;
        out
    }
}

/// What went wrong posing a body.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PoseError {
    #[error("{given} betas given but the model {model} has {available}")]
    TooManyBetas {
        given: usize,
        available: usize,
        model: String,
    },
    #[error("{given} expression coefficients given but the model {model} has {available}")]
    TooManyExpression {
        given: usize,
        available: usize,
        model: String,
    },
    #[error("non-finite {what} value at index {index}")]
    NonFinite { what: &'static str, index: usize },
    #[error("the model {model} has no vertex that follows joint {joint} most (a fingertip)")]
    NoFingertip { joint: usize, model: String },
}

/// A body with its shape applied: shaped rest vertices and rest joints.
///
/// Reuse it for every frame of a sequence with the same betas.
#[derive(Debug, Clone)]
pub struct ShapedBody<'m> {
    model: &'m BodyModel,
    /// Rest vertices after shape and expression blend shapes.
    pub v_shaped: Vec<Vec3>,
    /// Rest joints regressed from `v_shaped`.
    pub rest_joints: [Vec3; NUM_JOINTS],
}

/// A posed body: vertices, joints and each joint's world transform.
#[derive(Debug, Clone)]
pub struct PosedBody {
    pub vertices: Vec<Vec3>,
    pub joints: [Vec3; NUM_JOINTS],
    /// `world_from_joint[j]` maps joint-local rest offsets to the posed world (rotation is the
    /// joint's accumulated rotation; translation the posed joint position).
    pub world_from_joint: [Affine3; NUM_JOINTS],
}

/// The kinematic result alone: joints and transforms, no vertices.
#[derive(Debug, Clone)]
pub struct PosedSkeleton {
    pub joints: [Vec3; NUM_JOINTS],
    pub world_from_joint: [Affine3; NUM_JOINTS],
}

impl Default for PosedSkeleton {
    /// Every joint at the origin with the identity transform: a buffer for
    /// [`ShapedBody::skeleton_into`].
    fn default() -> Self {
        Self {
            joints: [Vec3::ZERO; NUM_JOINTS],
            world_from_joint: [Affine3::IDENTITY; NUM_JOINTS],
        }
    }
}

impl BodyModel {
    /// Applies betas and expression: the per-sequence part of skinning.
    pub fn shape(&self, betas: &[Real], expression: &[Real]) -> Result<ShapedBody<'_>, PoseError> {
        let coeffs = self.blend_coefficients(betas, expression)?;
        let v_shaped: Vec<Vec3> = self
            .v_template
            .par_iter()
            .enumerate()
            .map(|(v, &t)| t + self.blend_offset(v, &coeffs))
            .collect();
        let rest_joints = regress_joints(&self.j_regressor, |v| v_shaped[v]);
        Ok(ShapedBody {
            model: self,
            v_shaped,
            rest_joints,
        })
    }

    /// Rest joints for the given shape, computing blend shapes only at regressor vertices.
    pub fn rest_joints(
        &self,
        betas: &[Real],
        expression: &[Real],
    ) -> Result<[Vec3; NUM_JOINTS], PoseError> {
        let coeffs = self.blend_coefficients(betas, expression)?;
        Ok(regress_joints(&self.j_regressor, |v| {
            self.v_template[v] + self.blend_offset(v, &coeffs)
        }))
    }

    /// Full skinning of one body (shape + pose), as `smplx` computes it.
    pub fn pose(&self, params: &BodyParams) -> Result<PosedBody, PoseError> {
        self.shape(&params.betas, &params.expression)?
            .pose(&params.pose, params.transl)
    }

    /// Full skinning of many bodies in parallel.
    pub fn pose_batch(&self, params: &[BodyParams]) -> Result<Vec<PosedBody>, PoseError> {
        params.par_iter().map(|p| self.serial_pose(p)).collect()
    }

    /// Skinning of one body on the calling thread only (for batches, parallel across bodies).
    fn serial_pose(&self, params: &BodyParams) -> Result<PosedBody, PoseError> {
        let coeffs = self.blend_coefficients(&params.betas, &params.expression)?;
        let v_shaped: Vec<Vec3> = self
            .v_template
            .iter()
            .enumerate()
            .map(|(v, &t)| t + self.blend_offset(v, &coeffs))
            .collect();
        let rest_joints = regress_joints(&self.j_regressor, |v| v_shaped[v]);
        let shaped = ShapedBody {
            model: self,
            v_shaped,
            rest_joints,
        };
        shaped.pose_with(&params.pose, params.transl, false)
    }

    /// Coefficients per column of `dirs` (betas and expression placed in their columns).
    fn blend_coefficients(
        &self,
        betas: &[Real],
        expression: &[Real],
    ) -> Result<Vec<(usize, Real)>, PoseError> {
        if betas.len() > self.num_betas() {
            return Err(PoseError::TooManyBetas {
                given: betas.len(),
                available: self.num_betas(),
                model: self.source.display().to_string(),
            });
        }
        if expression.len() > self.num_expression() {
            return Err(PoseError::TooManyExpression {
                given: expression.len(),
                available: self.num_expression(),
                model: self.source.display().to_string(),
            });
        }
        check_finite("betas", betas)?;
        check_finite("expression", expression)?;
        let shape = betas
            .iter()
            .enumerate()
            .map(|(i, &b)| (self.shape_cols.start + i, b));
        let expr = expression
            .iter()
            .enumerate()
            .map(|(i, &e)| (self.expression_cols.start + i, e));
        Ok(shape.chain(expr).filter(|&(_, c)| c != 0.0).collect())
    }

    #[inline]
    fn blend_offset(&self, v: usize, coeffs: &[(usize, Real)]) -> Vec3 {
        if coeffs.is_empty() {
            return Vec3::ZERO;
        }
        let d = self.num_dirs;
        let base = v * 3 * d;
        let (rx, ry, rz) = (
            &self.dirs[base..base + d],
            &self.dirs[base + d..base + 2 * d],
            &self.dirs[base + 2 * d..base + 3 * d],
        );
        let mut o = Vec3::ZERO;
        for &(c, w) in coeffs {
            o += Vec3::new(rx[c], ry[c], rz[c]) * w;
        }
        o
    }
}

impl ShapedBody<'_> {
    /// Height of the soles at rest: the lowest shaped rest vertex's y (the model's y-up frame).
    pub(crate) fn rest_sole_y(&self) -> Real {
        self.v_shaped
            .iter()
            .map(|v| v.y)
            .fold(Real::INFINITY, Real::min)
    }

    /// Poses the shaped body: pose correctives (if any), rigid chain, LBS, translation.
    pub fn pose(&self, pose: &[Real; POSE_DIM], transl: Vec3) -> Result<PosedBody, PoseError> {
        self.pose_with(pose, transl, true)
    }

    /// Joints and transforms only, no vertices (the motion loop's fast path).
    pub fn skeleton(
        &self,
        pose: &[Real; POSE_DIM],
        transl: Vec3,
    ) -> Result<PosedSkeleton, PoseError> {
        posed_skeleton(&self.rest_joints, pose, transl)
    }

    /// [`Self::skeleton`] written into `out` ([`posed_skeleton_into`]).
    pub(crate) fn skeleton_into(
        &self,
        pose: &[Real; POSE_DIM],
        transl: Vec3,
        out: &mut PosedSkeleton,
    ) -> Result<(), PoseError> {
        posed_skeleton_into(&self.rest_joints, pose, transl, out)
    }

    /// Posed positions of selected vertices only (e.g. body markers).
    pub(crate) fn pose_vertices(
        &self,
        skeleton: &PosedSkeleton,
        pose: &[Real; POSE_DIM],
        vertex_ids: &[u32],
    ) -> Vec<Vec3> {
        let feature = self
            .model
            .posedirs
            .as_ref()
            .map(|_| pose_feature(&joint_rotations(pose)));
        let skin = SkinTransforms::new(&skeleton.world_from_joint, &self.rest_joints);
        vertex_ids
            .iter()
            .map(|&v| {
                let v = v as usize;
                let mut p = self.v_shaped[v];
                if let (Some(pd), Some(f)) = (&self.model.posedirs, &feature) {
                    p += corrective_offset(pd, v, f);
                }
                skin.apply(&self.model.skin_weights[v], p)
            })
            .collect()
    }

    /// Poses a sequence of frames: the pose correctives of a batch of frames come from one f32
    /// matrix product (`features [B × 486] · posedirsᵀ`), so the 486 × V·3 corrective matrix is
    /// read once per batch of [`CORRECTIVE_BATCH`] frames instead of once per frame; skinning
    /// then runs per frame, frames in parallel. Without correctives every frame is posed
    /// directly, frames in parallel. The same results as [`ShapedBody::pose`] per frame (to
    /// f32 rounding of the correctives' sums).
    pub fn pose_sequence(
        &self,
        poses: &[[Real; POSE_DIM]],
        transl: &[Vec3],
    ) -> Result<Vec<PosedBody>, PoseError> {
        assert_eq!(poses.len(), transl.len(), "one translation per pose");
        let Some(posedirs) = &self.model.posedirs else {
            return poses
                .par_iter()
                .zip(transl)
                .map(|(pose, &t)| self.pose_with(pose, t, false))
                .collect();
        };
        let n = self.v_shaped.len() * 3;
        let mut out = Vec::with_capacity(poses.len());
        for (poses, transl) in poses
            .chunks(CORRECTIVE_BATCH)
            .zip(transl.chunks(CORRECTIVE_BATCH))
        {
            let b = poses.len();
            let mut features = vec![0f32; b * POSE_FEATURES];
            for (f, pose) in features.chunks_mut(POSE_FEATURES).zip(poses) {
                // Refused before the batch's product, not after it.
                check_finite("pose", pose)?;
                f.copy_from_slice(&pose_feature(&joint_rotations(pose)));
            }
            // offsets[n][b] = Σ_k posedirs[n][k] · features[b][k]; rows n split across threads.
            let mut offsets = vec![0f32; n * b];
            const ROWS: usize = 3 * 1024;
            offsets
                .par_chunks_mut(ROWS * b)
                .enumerate()
                .for_each(|(block, c)| {
                    let n0 = block * ROWS;
                    let rows = c.len() / b;
                    let a = &posedirs[n0 * POSE_FEATURES..(n0 + rows) * POSE_FEATURES];
                    // SAFETY: `a` is rows × 486 (row stride 486), `features` 486 × b read with
                    // row stride 1 and column stride 486, `c` rows × b (row stride b); all
                    // three slices hold exactly those elements.
                    unsafe {
                        matrixmultiply::sgemm(
                            rows,
                            POSE_FEATURES,
                            b,
                            1.0,
                            a.as_ptr(),
                            POSE_FEATURES as isize,
                            1,
                            features.as_ptr(),
                            1,
                            POSE_FEATURES as isize,
                            0.0,
                            c.as_mut_ptr(),
                            b as isize,
                            1,
                        );
                    }
                });
            let posed = (0..b)
                .into_par_iter()
                .map(|f| {
                    let offset = |v: usize| {
                        let at = |c: usize| offsets[(3 * v + c) * b + f] as Real;
                        Vec3::new(at(0), at(1), at(2))
                    };
                    self.skin(&poses[f], transl[f], offset, false)
                })
                .collect::<Result<Vec<_>, _>>()?;
            out.extend(posed);
        }
        Ok(out)
    }

    fn pose_with(
        &self,
        pose: &[Real; POSE_DIM],
        transl: Vec3,
        parallel: bool,
    ) -> Result<PosedBody, PoseError> {
        match &self.model.posedirs {
            Some(pd) => {
                let feature = pose_feature(&joint_rotations(pose));
                self.skin(
                    pose,
                    transl,
                    |v| corrective_offset(pd, v, &feature),
                    parallel,
                )
            }
            None => self.skin(pose, transl, |_| Vec3::ZERO, parallel),
        }
    }

    /// LBS of the shaped vertices plus `offset(v)` (the pose correctives).
    fn skin(
        &self,
        pose: &[Real; POSE_DIM],
        transl: Vec3,
        offset: impl Fn(usize) -> Vec3 + Sync,
        parallel: bool,
    ) -> Result<PosedBody, PoseError> {
        let skeleton = posed_skeleton(&self.rest_joints, pose, transl)?;
        let skin = SkinTransforms::new(&skeleton.world_from_joint, &self.rest_joints);
        let model = self.model;
        let vertex = |v: usize| skin.apply(&model.skin_weights[v], self.v_shaped[v] + offset(v));
        let n = self.v_shaped.len();
        let vertices: Vec<Vec3> = if parallel {
            (0..n)
                .into_par_iter()
                .with_min_len(2048)
                .map(vertex)
                .collect()
        } else {
            (0..n).map(vertex).collect()
        };
        Ok(PosedBody {
            vertices,
            joints: skeleton.joints,
            world_from_joint: skeleton.world_from_joint,
        })
    }
}

/// Per-joint skinning transforms `world_from_joint · translate(−J_rest)` (with `transl`).
struct SkinTransforms {
    mats: [Affine3; NUM_JOINTS],
}

impl SkinTransforms {
    fn new(world_from_joint: &[Affine3; NUM_JOINTS], rest_joints: &[Vec3; NUM_JOINTS]) -> Self {
        let mut mats = [Affine3::IDENTITY; NUM_JOINTS];
        for j in 0..NUM_JOINTS {
            let m = world_from_joint[j];
            mats[j] = Affine3 {
                matrix3: m.matrix3,
                translation: m.translation - m.matrix3 * rest_joints[j],
            };
        }
        Self { mats }
    }

    #[inline]
    fn apply(&self, weights: &[(u32, Real)], p: Vec3) -> Vec3 {
        // Blend the matrices, then transform once (as smplx does: T = W·A; v = T·v_posed).
        let mut m = Mat3::ZERO;
        let mut t = Vec3::ZERO;
        for &(j, w) in weights {
            let a = &self.mats[j as usize];
            m += a.matrix3 * w;
            t += a.translation * w;
        }
        m * p + t
    }
}

/// Rigid kinematic chain from rest joints and a pose (smplx `batch_rigid_transform`).
pub(crate) fn posed_skeleton(
    rest_joints: &[Vec3; NUM_JOINTS],
    pose: &[Real; POSE_DIM],
    transl: Vec3,
) -> Result<PosedSkeleton, PoseError> {
    let mut skeleton = PosedSkeleton::default();
    posed_skeleton_into(rest_joints, pose, transl, &mut skeleton)?;
    Ok(skeleton)
}

/// [`posed_skeleton`] written into `out` (a sequence's frames posed one after another into one
/// buffer, without moving 6 KB of transforms per frame). `out` is left as it was on an error.
pub(crate) fn posed_skeleton_into(
    rest_joints: &[Vec3; NUM_JOINTS],
    pose: &[Real; POSE_DIM],
    transl: Vec3,
    out: &mut PosedSkeleton,
) -> Result<(), PoseError> {
    check_finite("pose", pose)?;
    check_finite("transl", &transl.to_array())?;
    let rots = joint_rotations(pose);
    let world_from_joint = &mut out.world_from_joint;
    for j in 0..NUM_JOINTS {
        let local = match PARENTS[j] {
            None => Affine3 {
                matrix3: rots[j],
                translation: rest_joints[j],
            },
            Some(p) => Affine3 {
                matrix3: rots[j],
                translation: rest_joints[j] - rest_joints[p],
            },
        };
        world_from_joint[j] = match PARENTS[j] {
            None => local,
            Some(p) => world_from_joint[p] * local,
        };
    }
    for m in world_from_joint.iter_mut() {
        m.translation += transl;
    }
    for (joint, m) in out.joints.iter_mut().zip(&out.world_from_joint) {
        *joint = m.translation;
    }
    Ok(())
}

fn joint_rotations(pose: &[Real; POSE_DIM]) -> [Mat3; NUM_JOINTS] {
    let aa: [Vec3; NUM_JOINTS] =
        std::array::from_fn(|j| Vec3::new(pose[3 * j], pose[3 * j + 1], pose[3 * j + 2]));
    let mut rotations = [Mat3::IDENTITY; NUM_JOINTS];
    axis_angles_to_matrices(&aa, &mut rotations);
    rotations
}

/// `vec(R_j − I)` for joints 1..55, row-major per matrix (the order `smplx` flattens in), in
/// f32 like the correctives it multiplies.
fn pose_feature(rots: &[Mat3; NUM_JOINTS]) -> Vec<f32> {
    let mut f = Vec::with_capacity(POSE_FEATURES);
    for r in &rots[1..] {
        let d = *r - Mat3::IDENTITY;
        f.extend(d.transpose().to_cols_array().map(|x| x as f32));
    }
    f
}

/// Frames per corrective matrix product in [`ShapedBody::pose_sequence`].
pub const CORRECTIVE_BATCH: usize = 64;

#[inline]
fn corrective_offset(posedirs: &[f32], v: usize, feature: &[f32]) -> Vec3 {
    let row = |c: usize| {
        let base = (v * 3 + c) * POSE_FEATURES;
        posedirs[base..base + POSE_FEATURES]
            .iter()
            .zip(feature)
            .map(|(a, b)| a * b)
            .sum::<f32>() as Real
    };
    Vec3::new(row(0), row(1), row(2))
}

fn regress_joints(
    j_regressor: &[Vec<(u32, Real)>],
    vertex: impl Fn(usize) -> Vec3,
) -> [Vec3; NUM_JOINTS] {
    std::array::from_fn(|j| {
        j_regressor[j]
            .iter()
            .map(|&(v, w)| vertex(v as usize) * w)
            .sum()
    })
}

fn check_finite(what: &'static str, values: &[Real]) -> Result<(), PoseError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(PoseError::NonFinite { what, index }),
        None => Ok(()),
    }
}
