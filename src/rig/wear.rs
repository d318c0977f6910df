//! How a headset sits on a head: people wear head-mounted devices a little differently (paper
//! Sec. 4.2, S5.3), so each wearer's rig is moved by a small rigid offset in the CPF frame,
//! drawn per wearer and sequence from a seed; `world_from_cam = world_from_cpf ·
//! cpf_from_headset · cpf_from_cam`. The offset is recorded exactly in the annotations, whose
//! camera poses are the moved ones.

use glam::{DQuat, DVec3, EulerRot};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::math::random::uniform_open01;
use crate::math::Affine3;

/// The ranges offsets are drawn from: each translation component uniform in
/// ±`translation_m`, each rotation angle (about the CPF's x, y and z axes, in that order)
/// uniform in ±`rotation_rad`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HeadsetWear {
    pub translation_m: f64,
    pub rotation_rad: f64,
    pub seed: u64,
}

/// One wearer's offset.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WearOffset {
    /// Translation in the CPF frame (m; x left, y up, z forward).
    pub translation_m: [f64; 3],
    /// Rotation angles about the CPF's x, y, z axes (rad), applied x first.
    pub rotation_xyz_rad: [f64; 3],
    /// The same as a row-major 4×4: headset frame (the rig's CPF) to the body's CPF.
    pub t_cpf_headset: [[f64; 4]; 4],
}

impl WearOffset {
    /// No offset: the rig as its file places it.
    pub fn none() -> Self {
        Self::new([0.0; 3], [0.0; 3])
    }

    fn new(translation_m: [f64; 3], rotation_xyz_rad: [f64; 3]) -> Self {
        let m = transform(translation_m, rotation_xyz_rad);
        let (r, t) = (m.matrix3, m.translation);
        Self {
            translation_m,
            rotation_xyz_rad,
            t_cpf_headset: [
                [r.x_axis.x, r.y_axis.x, r.z_axis.x, t.x],
                [r.x_axis.y, r.y_axis.y, r.z_axis.y, t.y],
                [r.x_axis.z, r.y_axis.z, r.z_axis.z, t.z],
                [0.0, 0.0, 0.0, 1.0],
            ],
        }
    }

    /// The offset as a transform from the headset frame to the CPF.
    pub fn cpf_from_headset(&self) -> Affine3 {
        transform(self.translation_m, self.rotation_xyz_rad)
    }
}

fn transform(translation_m: [f64; 3], [a, b, c]: [f64; 3]) -> Affine3 {
    Affine3::from_rotation_translation(
        DQuat::from_euler(EulerRot::XYZ, a, b, c),
        DVec3::from_array(translation_m),
    )
}

impl HeadsetWear {
    /// The offset of wearer `index` (its place among the sequence's agents), the same for the
    /// same seed and index.
    pub fn draw(&self, index: usize) -> WearOffset {
        let mut rng = ChaCha8Rng::seed_from_u64(
            self.seed.rotate_left(29) ^ (index as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        let mut symmetric = |half: f64| half * (2.0 * uniform_open01(&mut rng) - 1.0);
        let t = [
            symmetric(self.translation_m),
            symmetric(self.translation_m),
            symmetric(self.translation_m),
        ];
        let r = [
            symmetric(self.rotation_rad),
            symmetric(self.rotation_rad),
            symmetric(self.rotation_rad),
        ];
        WearOffset::new(t, r)
    }
}
