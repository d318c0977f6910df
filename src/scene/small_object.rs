//! Small objects people pick up: what each is ([`ObjectKind`]: a cup, a tin, a bottle), its
//! solid ([`ObjectShape`], which Blender draws), its footprint and the heights it comes in
//! (together 7–32 cm: whatever height a palm reaches down to, some object fits under it). All
//! are narrower than a hand, which closes round them from above: over a box as wide as a
//! parcel the closed fingers entered its top at every height it comes in.

use serde::{Deserialize, Serialize};

/// A held object's solid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectShape {
    /// Upright, round: its size's x and y are the diameter.
    Cylinder,
}

/// What a person may pick up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectKind {
    Cup,
    Tin,
    Bottle,
}

impl ObjectKind {
    pub(crate) const ALL: [ObjectKind; 3] = [ObjectKind::Cup, ObjectKind::Tin, ObjectKind::Bottle];

    pub(crate) fn name(self) -> &'static str {
        match self {
            ObjectKind::Cup => "cup",
            ObjectKind::Tin => "tin",
            ObjectKind::Bottle => "bottle",
        }
    }

    pub(crate) fn shape(self) -> ObjectShape {
        ObjectShape::Cylinder
    }

    /// Full extents along its own x and y (m).
    pub(crate) fn footprint_m(self) -> [f64; 2] {
        match self {
            ObjectKind::Cup => [0.08, 0.08],
            ObjectKind::Tin => [0.075, 0.075],
            ObjectKind::Bottle => [0.07, 0.07],
        }
    }

    /// The lowest and highest it comes in (m): a mug to a tall cup, a tuna tin to a coffee
    /// tin, a small bottle to a wine bottle.
    pub(crate) fn heights_m(self) -> [f64; 2] {
        match self {
            ObjectKind::Cup => [0.08, 0.12],
            ObjectKind::Tin => [0.07, 0.16],
            ObjectKind::Bottle => [0.18, 0.32],
        }
    }

    /// The width the hand closes round (m): across its top, the narrower way.
    pub(crate) fn grip_m(self) -> f64 {
        let [x, y] = self.footprint_m();
        x.min(y)
    }
}
