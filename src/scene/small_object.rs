//! Small objects people pick up: what each is ([`ObjectKind`]: a cup, a tin, a bottle, a
//! parcel), its solid ([`ObjectShape`], which Blender draws) and its size.

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

    /// Full extents along its own x, y and up (m).
    pub(crate) fn size_m(self) -> [f64; 3] {
        match self {
            ObjectKind::Cup => [0.08, 0.08, 0.095],
            ObjectKind::Tin => [0.075, 0.075, 0.115],
            ObjectKind::Bottle => [0.07, 0.07, 0.24],
            ObjectKind::Parcel => [0.22, 0.16, 0.12],
        }
    }

    /// The width the hand closes round (m): across its top, the narrower way.
    pub(crate) fn grip_m(self) -> f64 {
        let [x, y, _] = self.size_m();
        x.min(y)
    }
}
