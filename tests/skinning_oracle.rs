//! Skinning against the `smplx` package (golden data from tools/make_skinning_golden.py):
//! our shipped model and a random model with official SMPL-X sizes, ≤ 1e-5 m everywhere.

mod common;

use common::*;
use egogen::body::{BodyModel, BodyParams, POSE_DIM};
use egogen::math::Vec3;

const TOL_M: f64 = 1e-5;

fn check_against_golden(model: &BodyModel, golden: &Golden) -> (f64, f64) {
    let g = golden;
    let nv = model.num_vertices();
    let params: Vec<BodyParams> = (0..g.n_bodies)
        .map(|b| BodyParams {
            betas: g.betas[b * g.n_betas..(b + 1) * g.n_betas].to_vec(),
            expression: g.expression[b * g.n_expr..(b + 1) * g.n_expr].to_vec(),
            pose: g.poses[b * POSE_DIM..(b + 1) * POSE_DIM]
                .try_into()
                .unwrap(),
            transl: Vec3::new(g.transl[3 * b], g.transl[3 * b + 1], g.transl[3 * b + 2]),
        })
        .collect();
    let bodies = model.pose_batch(&params).unwrap();
    let (mut max_v, mut max_j) = (0.0f64, 0.0f64);
    for (b, body) in bodies.iter().enumerate() {
        for j in 0..55 {
            let e = &g.joints[(b * 55 + j) * 3..(b * 55 + j) * 3 + 3];
            max_j = max_j.max(
                (body.joints[j] - Vec3::new(e[0], e[1], e[2]))
                    .abs()
                    .max_element(),
            );
        }
        for (k, &vi) in g.subset.iter().enumerate() {
            let e = &g.vertices_subset[(b * g.subset.len() + k) * 3..][..3];
            let d = body.vertices[vi as usize] - Vec3::new(e[0], e[1], e[2]);
            max_v = max_v.max(d.abs().max_element());
        }
        if b < g.n_full {
            for vi in 0..nv {
                let e = &g.vertices_full[(b * nv + vi) * 3..][..3];
                let d = body.vertices[vi] - Vec3::new(e[0] as f64, e[1] as f64, e[2] as f64);
                max_v = max_v.max(d.abs().max_element());
            }
        }
    }
    (max_v, max_j)
}

#[test]
fn default_model_matches_smplx() {
    let model = BodyModel::load(default_model_path()).unwrap();
    let golden = read_golden(&repo_root().join("tests/fixtures/skinning_golden_default.npz"));
    assert!(golden.n_bodies >= 100);
    let (max_v, max_j) = check_against_golden(&model, &golden);
    eprintln!("default model vs smplx: max vertex error {max_v:.3e} m, max joint error {max_j:.3e} m over {} bodies", golden.n_bodies);
    assert!(
        max_v <= TOL_M && max_j <= TOL_M,
        "vertex {max_v:e}, joint {max_j:e}"
    );
}

#[test]
fn random_official_shaped_model_matches_smplx() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("SMPLX_NEUTRAL.npz");
    write_npz(&path, &random_model_arrays());
    let model = BodyModel::load(&path).unwrap();
    assert_eq!(
        (
            model.num_vertices(),
            model.num_betas(),
            model.num_expression()
        ),
        (10475, 300, 100)
    );
    assert!(model.has_pose_correctives());
    let golden = read_golden(&repo_root().join("tests/fixtures/skinning_golden_random.npz"));
    assert!(golden.n_bodies >= 100);
    let (max_v, max_j) = check_against_golden(&model, &golden);
    eprintln!("random SMPL-X-shaped model vs smplx: max vertex error {max_v:.3e} m, max joint error {max_j:.3e} m over {} bodies", golden.n_bodies);
    assert!(
        max_v <= TOL_M && max_j <= TOL_M,
        "vertex {max_v:e}, joint {max_j:e}"
    );
}

/// A sequence posed in batches (the correctives of up to 64 frames from one matrix product)
/// agrees with posing each frame alone: 100 golden poses of one shape, more than one batch,
/// on the official-shaped model with (random, large) correctives, within 1e-6 m: both sum
/// the correctives in f32, in a different order.
#[test]
fn batched_sequence_matches_single_frames() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("SMPLX_NEUTRAL.npz");
    write_npz(&path, &random_model_arrays());
    let model = BodyModel::load(&path).unwrap();
    let g = read_golden(&repo_root().join("tests/fixtures/skinning_golden_random.npz"));
    let shaped = model.shape(&g.betas[..g.n_betas], &[]).unwrap();
    let poses: Vec<[f64; POSE_DIM]> = (0..g.n_bodies)
        .map(|b| {
            g.poses[b * POSE_DIM..(b + 1) * POSE_DIM]
                .try_into()
                .unwrap()
        })
        .collect();
    assert!(poses.len() > egogen::body::CORRECTIVE_BATCH);
    let transl: Vec<Vec3> = (0..poses.len())
        .map(|b| Vec3::new(g.transl[3 * b], g.transl[3 * b + 1], g.transl[3 * b + 2]))
        .collect();
    let batched = shaped.pose_sequence(&poses, &transl).unwrap();
    let mut max_d = 0.0f64;
    for (f, body) in batched.iter().enumerate() {
        let single = shaped.pose(&poses[f], transl[f]).unwrap();
        assert_eq!(single.joints, body.joints);
        for (a, b) in single.vertices.iter().zip(&body.vertices) {
            max_d = max_d.max((*a - *b).abs().max_element());
        }
    }
    eprintln!("batched vs single frames: max vertex difference {max_d:.2e} m");
    assert!(max_d < 1e-6, "{max_d}");
    // A non-finite pose is refused, not skinned.
    let mut bad = poses[..3].to_vec();
    bad[1][7] = f64::NAN;
    assert!(shaped.pose_sequence(&bad, &transl[..3]).is_err());
}
