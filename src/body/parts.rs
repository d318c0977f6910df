//! The body's parts a frame's segmentation tells apart within a person ([`BodyPart`]: each
//! hand, each forearm, the rest): each vertex is the part of the joint that carries most of its
//! skin weight — a hand is its wrist's and fingers' vertices, a forearm its elbow's (the elbow
//! joint turns the forearm).

use super::{joint, BodyModel};

/// A part of a person in the frame file's `segmentation.part` channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub(crate) enum BodyPart {
    /// Everything but the hands and forearms (and every pixel that is not a person's).
    Rest = 0,
    LeftHand = 1,
    RightHand = 2,
    LeftForearm = 3,
    RightForearm = 4,
}

/// First SMPL-X finger joint of each hand (left, right); each hand has 15.
const FINGERS_FROM: [usize; 2] = [25, 40];

impl BodyPart {
    /// The part a vertex mostly skinned to `joint` belongs to.
    pub(crate) fn of_joint(j: usize) -> BodyPart {
        match j {
            joint::LEFT_WRIST => BodyPart::LeftHand,
            joint::RIGHT_WRIST => BodyPart::RightHand,
            joint::LEFT_ELBOW => BodyPart::LeftForearm,
            joint::RIGHT_ELBOW => BodyPart::RightForearm,
            _ if (FINGERS_FROM[0]..FINGERS_FROM[0] + 15).contains(&j) => BodyPart::LeftHand,
            _ if (FINGERS_FROM[1]..FINGERS_FROM[1] + 15).contains(&j) => BodyPart::RightHand,
            _ => BodyPart::Rest,
        }
    }

    /// The hand's part (0: left, 1: right).
    pub(crate) fn hand(side: usize) -> BodyPart {
        [BodyPart::LeftHand, BodyPart::RightHand][side]
    }
}

/// Each face's part, in the model's face order: the part of two or three of its vertices, else
/// of its first (a face is one part, so a part's edge follows the mesh's edges: a rendered
/// pixel is never a blend of two parts).
pub(crate) fn face_parts(model: &BodyModel) -> Vec<BodyPart> {
    let parts = vertex_parts(model);
    model
        .faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| parts[v as usize]);
            if b == c {
                b
            } else {
                a
            }
        })
        .collect()
}

/// Each vertex's part, in the model's vertex order.
pub(crate) fn vertex_parts(model: &BodyModel) -> Vec<BodyPart> {
    model
        .skin_weights
        .iter()
        .map(|w| {
            w.iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(BodyPart::Rest, |&(j, _)| BodyPart::of_joint(j as usize))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hands_and_forearms_lie_where_they_are_on_the_rest_body() {
        let model = BodyModel::load(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/body/SMPLX_NEUTRAL.npz"),
        )
        .unwrap();
        let parts = vertex_parts(&model);
        let rest = model.rest_joints(&[], &[]).unwrap();
        let count = |p: BodyPart| parts.iter().filter(|&&q| q == p).count();
        // The model's rest pose is a T-pose along x: the left side at +x.
        for (side, sign) in [(0, 1.0), (1, -1.0)] {
            let hand = BodyPart::hand(side);
            let forearm = [BodyPart::LeftForearm, BodyPart::RightForearm][side];
            let wrist = rest[[joint::LEFT_WRIST, joint::RIGHT_WRIST][side]];
            let elbow = rest[[joint::LEFT_ELBOW, joint::RIGHT_ELBOW][side]];
            assert!(count(hand) > 500 && count(forearm) > 100, "{side}");
            for (v, &p) in parts.iter().enumerate() {
                let x = sign * model.v_template[v].x;
                if p == hand {
                    assert!(x > sign * wrist.x - 0.03, "{side}: hand vertex {v} at {x}");
                }
                if p == forearm {
                    assert!(
                        x > sign * elbow.x - 0.05 && x < sign * wrist.x + 0.05,
                        "{side}: forearm vertex {v} at {x}"
                    );
                }
            }
        }
        assert_eq!(count(BodyPart::LeftHand), count(BodyPart::RightHand));
    }
}
