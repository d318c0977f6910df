//! Small objects people pick up: what each is ([`ObjectKind`]: a cup, a tin, a bottle, a
//! parcel), its solid ([`ObjectShape`], which Blender draws), its footprint and the heights it
//! comes in (together 4–32 cm: whatever height a palm reaches down to, some object fits under
//! it).

use serde::{Deserialize, Serialize};

/// A held object's solid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectShape {
    /// Upright, round: its size's x and y are the diameter.
    Cylinder,
    Box,
}

/// What a person may pick up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectKind {
    Cup,
    Tin,
    Bottle,
    Parcel,
}

impl ObjectKind {
    pub(crate) const ALL: [ObjectKind; 4] = [
        ObjectKind::Cup,
        ObjectKind::Tin,
        ObjectKind::Bottle,
        ObjectKind::Parcel,
    ];

    pub(crate) fn name(self) -> &'static str {
        match self {
            ObjectKind::Cup => "cup",
            ObjectKind::Tin => "tin",
            ObjectKind::Bottle => "bottle",
            ObjectKind::Parcel => "parcel",
        }
    }

    pub(crate) fn shape(self) -> ObjectShape {
        match self {
            ObjectKind::Parcel => ObjectShape::Box,
            _ => ObjectShape::Cylinder,
        }
    }

    /// Full extents along its own x and y (m).
    pub(crate) fn footprint_m(self) -> [f64; 2] {
        match self {
            ObjectKind::Cup => [0.08, 0.08],
            ObjectKind::Tin => [0.075, 0.075],
            ObjectKind::Bottle => [0.07, 0.07],
            ObjectKind::Parcel => [0.22, 0.16],
        }
    }

    /// The lowest and highest it comes in (m): a mug to a tall cup, a tuna tin to a coffee
    /// tin, a small bottle to a wine bottle, a flat parcel to a shoebox.
    pub(crate) fn heights_m(self) -> [f64; 2] {
        match self {
            ObjectKind::Cup => [0.08, 0.12],
            ObjectKind::Tin => [0.07, 0.16],
            ObjectKind::Bottle => [0.18, 0.32],
            ObjectKind::Parcel => [0.04, 0.2],
        }
    }

    /// How far below the palm's centre its top must lie besides the palm's own clearance
    /// (m): the fingers close round a cup, a tin or a bottle outside it, but over a parcel's
    /// top, which they would enter from closer.
    pub(crate) fn finger_room_m(self) -> f64 {
        match self {
            ObjectKind::Parcel => 0.04,
            _ => 0.0,
        }
    }

    /// The width the hand closes round (m): across its top, the narrower way.
    pub(crate) fn grip_m(self) -> f64 {
        let [x, y] = self.footprint_m();
        x.min(y)
    }
}
