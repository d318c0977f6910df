//! Small objects people pick up: what each is ([`ObjectKind`]: a cup, a tin, a bottle), its
//! solid ([`ObjectShape`], which Blender draws), its footprint and the heights it comes in
//! (together 7–32 cm: whatever height a palm reaches down to, some object fits under it). All
//! are narrower than a hand, which closes round them from above: over a box as wide as a
//! parcel the closed fingers entered its top at every height it comes in. And the scene's
//! own small things narrow enough for a hand to close round ([`things_on_floor`]: a toy, a
//! bottle, a tin), which a pick-up may take instead.

use serde::{Deserialize, Serialize};

use super::object_class::ObjectClass;
use super::SceneMesh;
use crate::math::Vec3;

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

/// A small thing of the scene itself, standing on a floor: one a hand may take from above.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SceneThing {
    /// The scene object's name.
    pub name: String,
    /// Its axis-aligned box (world, m).
    pub min: Vec3,
    pub max: Vec3,
    /// Its triangles (world, m).
    pub triangles: Vec<[Vec3; 3]>,
}

impl SceneThing {
    /// The middle of its box.
    pub(crate) fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The middle of its top.
    pub(crate) fn top_centre(&self) -> Vec3 {
        Vec3::new(
            0.5 * (self.min.x + self.max.x),
            0.5 * (self.min.y + self.max.y),
            self.max.z,
        )
    }
}

/// Widest a scene thing a hand may take is, the narrower way across (m): the closed hand
/// wraps round it (the fingertips of a hand reaching to the floor hang 16–18 cm under the
/// wrist: over anything wider they go into it).
pub(crate) const THING_MAX_GRIP_M: f64 = 0.10;

/// Widest a scene thing a hand may take is, the wider way across (m).
pub(crate) const THING_MAX_ACROSS_M: f64 = 0.35;

/// Tallest a scene thing a hand may take is (m).
pub(crate) const THING_MAX_HEIGHT_M: f64 = 0.35;

/// The scene's objects small enough to pick up from above ([`THING_MAX_GRIP_M`] the
/// narrower way, [`THING_MAX_ACROSS_M`] the wider, [`THING_MAX_HEIGHT_M`] high at most)
/// whose name says nothing else than a small thing
/// (`scene::object_class`: a plant, a lamp, a piece of a wall is not one), in the scene's
/// order. Whether one stands on the floor a person is on is the caller's to say.
pub(crate) fn things_on_floor(mesh: &SceneMesh) -> Vec<SceneThing> {
    let mut boxes =
        vec![(Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)); mesh.objects.len()];
    for (t, o) in mesh.triangles.iter().zip(&mesh.triangle_object) {
        let Some(b) = (o.0 as usize).checked_sub(1).and_then(|k| boxes.get_mut(k)) else {
            continue;
        };
        for &v in t {
            let p = mesh.vertices[v as usize];
            b.0 = b.0.min(p);
            b.1 = b.1.max(p);
        }
    }
    let mut things: Vec<SceneThing> = mesh
        .objects
        .iter()
        .zip(boxes)
        .filter(|(o, (min, max))| {
            let size = *max - *min;
            size.x.is_finite()
                && size.x.min(size.y) <= THING_MAX_GRIP_M
                && size.x <= THING_MAX_ACROSS_M
                && size.y <= THING_MAX_ACROSS_M
                && size.z <= THING_MAX_HEIGHT_M
                && matches!(
                    ObjectClass::named(&o.name, o.label.as_deref()),
                    None | Some(ObjectClass::SmallObject)
                )
        })
        .map(|(o, (min, max))| SceneThing {
            name: o.name.clone(),
            min,
            max,
            triangles: Vec::new(),
        })
        .collect();
    // Each object's thing, by the object's index: one look-up a triangle.
    let mut thing_of = vec![None; mesh.objects.len()];
    for (k, thing) in things.iter().enumerate() {
        if let Some(o) = mesh.objects.iter().position(|o| o.name == thing.name) {
            thing_of[o] = Some(k);
        }
    }
    for (t, o) in mesh.triangles.iter().zip(&mesh.triangle_object) {
        let k = (o.0 as usize)
            .checked_sub(1)
            .and_then(|i| thing_of.get(i).copied().flatten());
        if let Some(k) = k {
            things[k]
                .triangles
                .push(t.map(|v| mesh.vertices[v as usize]));
        }
    }
    things
}

/// How far under the upper surface of `triangles` (any frame, z up) `p` lies (m): the
/// highest of them over `p`'s place less its height; 0 where none is over it or `p` lies
/// above them all.
pub(crate) fn depth_under_surface(triangles: &[[Vec3; 3]], p: Vec3) -> f64 {
    let top = triangles
        .iter()
        .filter_map(|[a, b, c]| {
            // Barycentric coordinates of p's place in the triangle seen from above.
            let (v0, v1, v2) = (*b - *a, *c - *a, p - *a);
            let det = v0.x * v1.y - v1.x * v0.y;
            if det.abs() < 1e-18 {
                return None;
            }
            let u = (v2.x * v1.y - v1.x * v2.y) / det;
            let v = (v0.x * v2.y - v2.x * v0.y) / det;
            (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then_some(a.z + u * v0.z + v * v1.z)
        })
        .fold(f64::NEG_INFINITY, f64::max);
    (top - p.z).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cube of side `s` standing at `(x, y)` on z = 0.
    fn cube(mesh: &mut SceneMesh, name: &str, x: f64, y: f64, s: [f64; 3]) {
        let v: Vec<Vec3> = (0..8)
            .map(|k| {
                Vec3::new(
                    x + s[0] * (k & 1) as f64,
                    y + s[1] * ((k >> 1) & 1) as f64,
                    s[2] * ((k >> 2) & 1) as f64,
                )
            })
            .collect();
        mesh.add_object(name, &v, &[[0, 1, 2], [5, 6, 7]]);
    }

    /// Small things are found by their size and a name that says nothing else; a big box,
    /// slippers wider than a hand, a tall box, a small plant and a lamp are not, and each
    /// thing's box and triangles are its own.
    #[test]
    fn small_things_are_found_by_size_and_name() {
        let mut mesh = SceneMesh::default();
        cube(&mut mesh, "thing_wood_toy_3", 1.0, 2.0, [0.08, 0.28, 0.06]);
        cube(&mut mesh, "box", 0.0, 0.0, [0.5, 0.3, 0.2]);
        cube(&mut mesh, "thing_slippers_4", 1.0, 2.0, [0.24, 0.28, 0.06]);
        cube(&mut mesh, "bottle_stand", 3.0, 0.0, [0.1, 0.1, 0.5]);
        cube(&mut mesh, "little_plant", 4.0, 0.0, [0.2, 0.2, 0.2]);
        cube(&mut mesh, "lamp_2", 5.0, 0.0, [0.2, 0.2, 0.2]);
        cube(&mut mesh, "toy", -7.0, 1e4, [0.09, 0.3, 0.3]);
        cube(&mut mesh, "wide_toy", -7.0, 1e4, [0.11, 0.11, 0.1]);
        let things = things_on_floor(&mesh);
        let names: Vec<&str> = things.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, ["thing_wood_toy_3", "toy"]);
        assert_eq!(things[0].min, Vec3::new(1.0, 2.0, 0.0));
        assert!((things[0].max - Vec3::new(1.08, 2.28, 0.06)).length() < 1e-12);
        let top = things[1].top_centre();
        assert!((top - Vec3::new(-6.955, 1e4 + 0.15, 0.3)).length() < 1e-9);
        assert_eq!(things[0].triangles.len(), 2);
        assert_eq!(things[0].triangles[0][1], Vec3::new(1.08, 2.0, 0.0));
    }

    /// Under a sloping triangle the depth is its height there less the point's; beside it,
    /// or above it, none.
    #[test]
    fn depth_is_measured_under_the_upper_surface() {
        let slope = [[
            Vec3::new(0.0, 0.0, 0.1),
            Vec3::new(1.0, 0.0, 0.2),
            Vec3::new(0.0, 1.0, 0.1),
        ]];
        let d = depth_under_surface(&slope, Vec3::new(0.5, 0.25, 0.05));
        assert!((d - 0.1).abs() < 1e-12, "{d}");
        assert_eq!(depth_under_surface(&slope, Vec3::new(0.9, 0.9, 0.0)), 0.0);
        assert_eq!(depth_under_surface(&slope, Vec3::new(0.1, 0.1, 0.5)), 0.0);
        let far = slope.map(|t| t.map(|v| v + Vec3::new(1e4, -1e4, 3.0)));
        let d = depth_under_surface(&far, Vec3::new(1e4 + 0.5, -1e4 + 0.25, 3.05));
        assert!((d - 0.1).abs() < 1e-9, "{d}");
    }
}
