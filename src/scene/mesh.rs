//! A scene as a triangle soup with per-triangle object ids (segmentation needs them later).

use crate::math::Vec3;

/// Stable id of a scene object: its index in [`SceneMesh::objects`] plus one (0 = none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObjectId(pub u32);

/// A named part of the scene (a glTF node, an OBJ object, a PLY file or, in a PLY whose faces
/// or vertices carry object ids, the faces of one id).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneObject {
    pub id: ObjectId,
    pub name: String,
    /// Its class where the file says (a Replica scan's `info_semantic.json`); else none.
    pub label: Option<String>,
    /// Its surface carries detail of its own: an image texture on a material of it (glTF
    /// base colour, an OBJ material's `map_Kd`) or vertex colours (glTF `COLOR_0`, a PLY's
    /// `red`/`green`/`blue`). `[render.materials] mode = "fill"` keeps these objects' materials.
    pub textured: bool,
    /// A material of it lets light through where it is hit (glTF `alphaMode` blend or mask,
    /// an OBJ material's `d` below 1 or `map_d`): replacing it would change the depth, so
    /// `[render.materials]` never does.
    pub see_through: bool,
}

/// World-space triangles (metres, z up) with the object each belongs to.
#[derive(Debug, Clone, Default)]
pub struct SceneMesh {
    pub vertices: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Object of each triangle.
    pub triangle_object: Vec<ObjectId>,
    pub objects: Vec<SceneObject>,
    /// For a PLY split by the object ids its faces or vertices carry: the object (an index
    /// into [`Self::objects`]) of each face of the file, in file order and before its
    /// polygons are cut into triangles — what Blender, which imports the file as one mesh,
    /// needs to split it the same way. `u32::MAX` for a face that made no triangle.
    pub file_face_objects: Option<Vec<u32>>,
}

impl SceneMesh {
    /// Adds an object's triangles (vertices already in world space); returns its id.
    pub fn add_object(
        &mut self,
        name: impl Into<String>,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> ObjectId {
        let id = ObjectId(self.objects.len() as u32 + 1);
        self.objects.push(SceneObject {
            id,
            name: name.into(),
            label: None,
            textured: false,
            see_through: false,
        });
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(vertices);
        self.triangles
            .extend(triangles.iter().map(|t| t.map(|i| i + base)));
        self.triangle_object
            .extend(std::iter::repeat_n(id, triangles.len()));
        id
    }

    /// Adds an axis-aligned box (closed, outward normals) as an object.
    pub fn add_box(&mut self, name: impl Into<String>, min: Vec3, max: Vec3) -> ObjectId {
        let (v, tris) = box_triangles(min, max);
        self.add_object(name, &v, &tris)
    }

    /// Adds a box standing on the floor plane, turned about z: its footprint (centre, half
    /// extents along its own axes, yaw in rad) from height `z0` to `z1`; returns its id.
    pub(crate) fn add_turned_box(
        &mut self,
        name: impl Into<String>,
        centre: glam::DVec2,
        half_extents: glam::DVec2,
        yaw_rad: f64,
        (z0, z1): (f64, f64),
    ) -> ObjectId {
        let rot = glam::DVec2::from_angle(yaw_rad);
        let before = self.vertices.len();
        let id = self.add_box(
            name,
            Vec3::new(-half_extents.x, -half_extents.y, z0),
            Vec3::new(half_extents.x, half_extents.y, z1),
        );
        for v in &mut self.vertices[before..] {
            let p = centre + rot.rotate(glam::DVec2::new(v.x, v.y));
            (v.x, v.y) = (p.x, p.y);
        }
        id
    }

    /// Writes the mesh as Wavefront OBJ (metres, z up, as [`super::load_scene`] reads an OBJ
    /// by default), one `o` object per scene object, atomically.
    pub fn write_obj(&self, path: &std::path::Path) -> std::io::Result<()> {
        use std::fmt::Write as _;
        let mut text = format!(
            "# egogen scene: {} objects, {} vertices, {} triangles; metres, z up\n",
            self.objects.len(),
            self.vertices.len(),
            self.triangles.len()
        );
        for v in &self.vertices {
            let _ = writeln!(text, "v {} {} {}", v.x, v.y, v.z);
        }
        let mut current = None;
        for (t, tri) in self.triangles.iter().enumerate() {
            let id = self.triangle_object[t];
            if current != Some(id) {
                current = Some(id);
                let name = (id.0 as usize)
                    .checked_sub(1)
                    .and_then(|k| self.objects.get(k))
                    .map_or("object", |o| o.name.as_str());
                let _ = writeln!(text, "o {name}");
            }
            let _ = writeln!(text, "f {} {} {}", tri[0] + 1, tri[1] + 1, tri[2] + 1);
        }
        crate::atomic_file::write_atomically(path, text.as_bytes())
    }

    /// Corner points of triangle `t`.
    pub(crate) fn triangle(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Axis-aligned bounds of all vertices, or `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        crate::math::point_bounds(&self.vertices)
    }

    /// How each object's surfaces face (in [`Self::objects`]' order): shares of its area whose
    /// normal is within 30° of up, of down, and the rest, and its height range.
    pub(crate) fn object_orientations(&self) -> Vec<ObjectOrientation> {
        let mut out = vec![
            ObjectOrientation {
                area_up: 0.0,
                area_down: 0.0,
                area_side: 0.0,
                z_min: f64::INFINITY,
                z_max: f64::NEG_INFINITY,
            };
            self.objects.len()
        ];
        let cos30 = 30f64.to_radians().cos();
        for t in 0..self.triangles.len() {
            let Some(o) = (self.triangle_object[t].0 as usize)
                .checked_sub(1)
                .and_then(|k| out.get_mut(k))
            else {
                continue;
            };
            let [a, b, c] = self.triangle(t);
            o.z_min = o.z_min.min(a.z.min(b.z).min(c.z));
            o.z_max = o.z_max.max(a.z.max(b.z).max(c.z));
            let n = (b - a).cross(c - a);
            let area = n.length();
            if !(area > 0.0) {
                continue;
            }
            let nz = n.z / area;
            if nz >= cos30 {
                o.area_up += area;
            } else if nz <= -cos30 {
                o.area_down += area;
            } else {
                o.area_side += area;
            }
        }
        for o in &mut out {
            let total = o.area_up + o.area_down + o.area_side;
            if total > 0.0 {
                o.area_up /= total;
                o.area_down /= total;
                o.area_side /= total;
            }
        }
        out
    }
}

/// How an object's surfaces face ([`SceneMesh::object_orientations`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectOrientation {
    /// Share of its area facing up (normal within 30° of +z).
    pub area_up: f64,
    /// Share facing down.
    pub area_down: f64,
    /// The rest: sideways.
    pub area_side: f64,
    /// Its lowest and highest points (m, z up); infinite for an object without triangles.
    pub z_min: f64,
    pub z_max: f64,
}

/// An axis-aligned box's 8 corners (corner `i` takes `max` on x, y, z where bit 0, 1, 2 of `i`
/// is set) and its 12 triangles, wound counter-clockwise seen from outside.
pub(crate) fn box_triangles(min: Vec3, max: Vec3) -> ([Vec3; 8], [[u32; 3]; 12]) {
    let corners = std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    });
    let quads: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut tris = [[0; 3]; 12];
    for (k, q) in quads.iter().enumerate() {
        tris[2 * k] = [q[0], q[1], q[2]];
        tris[2 * k + 1] = [q[0], q[2], q[3]];
    }
    (corners, tris)
}
