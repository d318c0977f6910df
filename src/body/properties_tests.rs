//! Property tests at the numerical extremes (they read the rotation and skinning
//! internals): rotations near 0 and π, degenerate 6D input, the batched conversions against
//! the one-at-a-time ones bit for bit, long transform chains, re-rooting, and skinning
//! invariants on the shipped model (its fast paths against full skinning, the CPF, the
//! markers).

use crate::body::{BodyModel, BodyParams};
use crate::math::rotation::{orthonormality_error, rot6d_to_matrix, skew};
use crate::math::{
    axis_angle_to_matrix, matrix_to_axis_angle, matrix_to_rot6d, Affine3, Mat3, Vec3,
};
use proptest::prelude::*;
use std::f64::consts::PI;
use std::sync::OnceLock;

fn unit_axis() -> impl Strategy<Value = Vec3> {
    (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0)
        .prop_filter("non-zero", |(x, y, z)| x * x + y * y + z * z > 1e-6)
        .prop_map(|(x, y, z)| Vec3::new(x, y, z).normalize())
}

/// Reference Rodrigues via the exponential series, accurate for any angle ≤ 4.
fn rodrigues_series(aa: Vec3) -> Mat3 {
    let k = skew(aa);
    let mut term = Mat3::IDENTITY;
    let mut sum = Mat3::IDENTITY;
    for n in 1..60 {
        term = term * k * (1.0 / n as f64);
        sum += term;
    }
    sum
}

fn max_abs(m: Mat3) -> f64 {
    m.to_cols_array()
        .iter()
        .fold(0.0, |a: f64, x| a.max(x.abs()))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn rodrigues_near_zero(axis in unit_axis(), exp in -16.0f64..-2.0) {
        let aa = axis * 10f64.powf(exp);
        let r = axis_angle_to_matrix(aa);
        prop_assert!(max_abs(r - rodrigues_series(aa)) < 1e-15);
        prop_assert!(orthonormality_error(r) < 1e-15);
        let back = matrix_to_axis_angle(r);
        prop_assert!((back - aa).length() <= 1e-15 + 1e-9 * aa.length());
    }

    #[test]
    fn rodrigues_near_pi(axis in unit_axis(), exp in -12.0f64..-1.0, sign in prop::bool::ANY) {
        let eps = 10f64.powf(exp) * if sign { 1.0 } else { -1.0 };
        let aa = axis * (PI + eps);
        let r = axis_angle_to_matrix(aa);
        prop_assert!(max_abs(r - rodrigues_series(aa)) < 1e-13);
        prop_assert!(orthonormality_error(r) < 1e-14);
        // Round trip returns an angle in [0, π] describing the same rotation.
        let back = matrix_to_axis_angle(r);
        prop_assert!(back.length() <= PI + 1e-12);
        prop_assert!(max_abs(axis_angle_to_matrix(back) - r) < 1e-7, "{:?} vs {:?}", back, aa);
    }

    #[test]
    fn rot6d_round_trip(axis in unit_axis(), angle in 0.0f64..PI) {
        let r = axis_angle_to_matrix(axis * angle);
        prop_assert!(max_abs(rot6d_to_matrix(matrix_to_rot6d(r)) - r) < 1e-14);
    }

    #[test]
    fn rot6d_degenerate_input_gives_rotation(
        a in prop::array::uniform3(-1e3f64..1e3),
        t in -1e3f64..1e3,
        noise_exp in -30.0f64..-6.0,
        scale_exp in -150.0f64..150.0,
    ) {
        // Second column (nearly) parallel to the first, at extreme scales.
        let s = 10f64.powf(scale_exp);
        let n = 10f64.powf(noise_exp);
        let d6 = [a[0] * s, a[1] * s, a[2] * s, (a[0] * t + n) * s, a[1] * t * s, (a[2] * t - n) * s];
        let r = rot6d_to_matrix(d6);
        prop_assert!(r.is_finite());
        prop_assert!(orthonormality_error(r) < 1e-12, "err {}", orthonormality_error(r));
        prop_assert!((r.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn rot6d_side_by_side_gives_the_same_bits(
        rows in prop::collection::vec(
            (prop::array::uniform6(-1e3f64..1e3), 0u8..5, -150.0f64..150.0),
            1..40,
        ),
    ) {
        // Ordinary, parallel, vanishing, zero and tiny or huge 6D vectors mixed in one call.
        let d6: Vec<[f64; 6]> = rows
            .iter()
            .map(|(v, kind, scale_exp)| {
                let s = 10f64.powf(*scale_exp);
                let mut d = v.map(|x| x * s);
                match kind {
                    1 => {
                        let parallel = [d[0] * 2.0, d[1] * 2.0, d[2] * 2.0];
                        d[3..].copy_from_slice(&parallel);
                    }
                    2 => d[..3].fill(0.0),
                    3 => d.fill(0.0),
                    4 => {
                        let nearly = [d[0] + 1e-9 * s, d[1], d[2]];
                        d[3..].copy_from_slice(&nearly);
                    }
                    _ => {}
                }
                d
            })
            .collect();
        let mut side_by_side = vec![Mat3::ZERO; d6.len()];
        crate::math::rotation::rot6d_to_matrices(&d6, &mut side_by_side);
        for (d, m) in d6.iter().zip(&side_by_side) {
            let one = rot6d_to_matrix(*d).to_cols_array().map(f64::to_bits);
            prop_assert_eq!(m.to_cols_array().map(f64::to_bits), one, "{:?}", d);
        }
    }

    #[test]
    fn axis_angles_side_by_side_give_the_same_bits(
        rows in prop::collection::vec((unit_axis(), 0u8..4, 0.0f64..1.0), 1..70),
    ) {
        // Angles of zero, below the series' 1e-4, ordinary ones, and at and near π (where
        // matrix → axis-angle takes its other branch), mixed in one call both ways.
        let aa: Vec<Vec3> = rows
            .iter()
            .map(|(axis, kind, u)| {
                *axis * match kind {
                    0 => 0.0,
                    1 => u * 1e-4,
                    2 => u * 3.0,
                    _ => PI - u * 1e-3,
                }
            })
            .collect();
        let mut matrices = vec![Mat3::ZERO; aa.len()];
        crate::math::rotation::axis_angles_to_matrices(&aa, &mut matrices);
        let bits = |m: &Mat3| m.to_cols_array().map(f64::to_bits);
        for (a, m) in aa.iter().zip(&matrices) {
            prop_assert_eq!(bits(m), bits(&axis_angle_to_matrix(*a)), "{:?}", a);
        }
        let mut back = vec![Vec3::ZERO; aa.len()];
        crate::math::rotation::matrices_to_axis_angles(&matrices, &mut back);
        for (m, b) in matrices.iter().zip(&back) {
            prop_assert_eq!(
                b.to_array().map(f64::to_bits),
                matrix_to_axis_angle(*m).to_array().map(f64::to_bits),
                "{:?}",
                m
            );
        }
    }

    #[test]
    fn long_chains_stay_orthonormal(seed in 0u64..1000) {
        // 100 000 random rigid transforms composed, as far longer rollouts would.
        let mut m = Affine3::IDENTITY;
        for i in 0..100_000u64 {
            let u = |k: u64| uniform(seed, 4 * i + k) * 2.0 - 1.0;
            let aa = Vec3::new(u(0), u(1), u(2)) * 3.0;
            m *= Affine3 { matrix3: axis_angle_to_matrix(aa), translation: Vec3::splat(u(3)) };
        }
        let err = orthonormality_error(m.matrix3);
        prop_assert!(err < 1e-11, "orthonormality error after 1e5 products: {err:e}");
    }
}

/// Orthonormality error after a very long chain, printed for the docs.
#[test]
fn report_chain_orthonormality_error() {
    let mut m = Mat3::IDENTITY;
    let mut worst = 0.0f64;
    for i in 0..1_000_000u64 {
        let u = |k: u64| uniform(7, 3 * i + k) * 2.0 - 1.0;
        m *= axis_angle_to_matrix(Vec3::new(u(0), u(1), u(2)) * 3.0);
        worst = worst.max(orthonormality_error(m));
    }
    eprintln!("orthonormality error over 1e6 composed rotations: max {worst:.2e}");
    assert!(worst < 1e-10);
}

fn model() -> &'static BodyModel {
    static MODEL: OnceLock<BodyModel> = OnceLock::new();
    MODEL.get_or_init(|| {
        BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .expect("shipped model loads")
    })
}

fn random_params(seed: u64, spread: f64) -> BodyParams {
    let mut p = BodyParams::default();
    for (i, v) in p.pose.iter_mut().enumerate() {
        *v = (uniform(seed, i as u64) * 2.0 - 1.0) * spread;
    }
    p.betas = (0..10)
        .map(|i| (uniform(seed + 1, i) * 2.0 - 1.0) * 3.0)
        .collect();
    p.transl = Vec3::new(0.3, -1.0, 2.0);
    p
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// transl' = R (transl + J0) − J0 + t moves the posed body rigidly, even far from origin.
    #[test]
    fn rerooting_moves_body_rigidly(seed in 0u64..10_000, axis in unit_axis(), angle in 0.0f64..PI, far in 0.0f64..1e4) {
        let m = model();
        let p = random_params(seed, 0.6);
        let world_from_old = Affine3 { matrix3: axis_angle_to_matrix(axis * angle), translation: Vec3::new(far, -far, 0.5 * far) };
        let rest_pelvis = m.rest_joints(&p.betas, &[]).unwrap()[0];
        let moved = m.pose(&p.moved_rigidly(world_from_old, rest_pelvis)).unwrap();
        let original = m.pose(&p).unwrap();
        let err = original.vertices.iter().zip(&moved.vertices)
            .map(|(a, b)| (world_from_old.transform_point3(*a) - *b).length())
            .fold(0.0, f64::max);
        prop_assert!(err < 1e-9 * (1.0 + far), "max error {err:e} m");
    }

    /// World rotations of every joint stay orthonormal for arbitrary poses (angles up to 4π).
    #[test]
    fn posed_joint_frames_are_orthonormal(seed in 0u64..10_000) {
        let m = model();
        let p = random_params(seed, 4.0 * PI);
        let s = m.shape(&p.betas, &[]).unwrap().skeleton(&p.pose, p.transl).unwrap();
        for f in &s.world_from_joint {
            prop_assert!(orthonormality_error(f.matrix3) < 1e-13);
        }
    }
}

#[test]
fn fast_paths_agree_with_full_skinning() {
    let m = model();
    let p = random_params(3, 0.8);
    let full = m.pose(&p).unwrap();
    let shaped = m.shape(&p.betas, &[]).unwrap();
    let skel = shaped.skeleton(&p.pose, p.transl).unwrap();
    for j in 0..55 {
        assert!((skel.joints[j] - full.joints[j]).length() < 1e-12);
    }
    let ids: Vec<u32> = (0..m.num_vertices() as u32).step_by(97).collect();
    let some = shaped.pose_vertices(&skel, &p.pose, &ids);
    for (k, &v) in ids.iter().enumerate() {
        assert!((some[k] - full.vertices[v as usize]).length() < 1e-12);
    }
    let rest = m.rest_joints(&p.betas, &[]).unwrap();
    assert!((rest[15] - shaped.rest_joints[15]).length() < 1e-12);
}

#[test]
fn cpf_follows_the_head_and_is_level_at_rest() {
    use crate::body::{joint, CpfCalibration};
    let m = model();
    let shaped = m.shape(&[], &[]).unwrap();
    let cal = CpfCalibration::from_rest_joints(&shaped.rest_joints);
    let rest = shaped.skeleton(&[0.0; 165], Vec3::ZERO).unwrap();
    let cpf = cal.world_from_cpf(&rest);
    assert!(
        max_abs(cpf.matrix3 - Mat3::IDENTITY) < 1e-12,
        "rest CPF axes are the body axes"
    );
    let mid = (rest.joints[joint::LEFT_EYE] + rest.joints[joint::RIGHT_EYE]) * 0.5;
    assert!((cpf.translation - mid).length() < 1e-12);
    // A posed head: the CPF rotates exactly with the head joint (eyes are rigid children).
    let p = random_params(11, 0.7);
    let s = m.shape(&p.betas, &[]).unwrap();
    let cal = CpfCalibration::from_rest_joints(&s.rest_joints);
    let sk = s.skeleton(&p.pose, p.transl).unwrap();
    let cpf = cal.world_from_cpf(&sk);
    assert!(max_abs(cpf.matrix3 - sk.world_from_joint[joint::HEAD].matrix3) < 1e-9);
    assert!(orthonormality_error(cpf.matrix3) < 1e-13);
}

#[test]
fn markers_are_spread_and_fast_path_matches_mesh() {
    use crate::body::{farthest_point_markers, NUM_MARKERS};
    let m = model();
    let ids = farthest_point_markers(m, NUM_MARKERS);
    assert_eq!(ids.len(), NUM_MARKERS);
    let mut sorted = ids.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), NUM_MARKERS, "distinct vertices");
    // Spread: no two markers closer than 3 cm on a ~1.7 m body.
    for (i, &a) in ids.iter().enumerate() {
        for &b in &ids[i + 1..] {
            assert!(m.v_template[a as usize].distance(m.v_template[b as usize]) > 0.03);
        }
    }
    let p = random_params(5, 0.6);
    let shaped = m.shape(&p.betas, &[]).unwrap();
    let frame = shaped.marker_frame(&p.pose, p.transl, &ids).unwrap();
    let full = m.pose(&p).unwrap();
    for (k, &v) in ids.iter().enumerate() {
        assert!((frame.markers[k] - full.vertices[v as usize]).length() < 1e-12);
    }
}

/// U(stream, i) in [0, 1) from SplitMix64 (the integration tests' own draw).
fn uniform(stream: u64, i: u64) -> f64 {
    let mut z = ((stream << 40) + i).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 * 2f64.powi(-53)
}
