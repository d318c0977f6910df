//! Reading scene files: glTF/GLB (`gltf`), OBJ (`tobj`), PLY (`ply-rs-bw`), into a
//! [`SceneMesh`] in metres with z up.
//!
//! Up axis: glTF is y up by specification, so `.gltf`/`.glb` default to [`UpAxis::Y`]; OBJ and
//! PLY default to [`UpAxis::Z`] (scanned scenes mostly are). A y-up point `(x, y, z)` becomes
//! `(x, −z, y)` in the z-up world. Units: metres by default (glTF's by specification); a file
//! in other units is scaled by its [`SceneFrame::unit_m`] (0.01 for centimetres).
//!
//! This file holds the frame, the errors, [`load_scene`] and the checks of a loaded scene (its
//! frame warning, its walkable map); each format's reader is its own file: `gltf_file`,
//! `obj_file`, `ply_file`.

mod gltf_file;
mod obj_file;
mod ply_file;

use std::path::{Path, PathBuf};

use super::mesh::SceneMesh;
use crate::math::Vec3;
use gltf_file::read_gltf;
use obj_file::read_obj;
use ply_file::{read_ply, replica_labels, PlyIds, NYU40_CLASSES};

/// Which axis of the file points up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    Y,
    Z,
}

impl UpAxis {
    /// The default for a file, from its extension.
    pub(crate) fn default_for(path: &Path) -> UpAxis {
        match extension(path).as_str() {
            "gltf" | "glb" => UpAxis::Y,
            _ => UpAxis::Z,
        }
    }

    /// The axis named `"y"` or `"z"`, as configs and flags name it; none for any other name.
    pub(crate) fn from_name(name: &str) -> Option<UpAxis> {
        match name {
            "y" => Some(UpAxis::Y),
            "z" => Some(UpAxis::Z),
            _ => None,
        }
    }

    /// The axis as configs and Blender's side name it: `"y"` or `"z"`.
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::Y => "y",
            UpAxis::Z => "z",
        }
    }

    fn to_z_up(self, p: [f64; 3]) -> Vec3 {
        match self {
            UpAxis::Z => Vec3::new(p[0], p[1], p[2]),
            UpAxis::Y => Vec3::new(p[0], -p[2], p[1]),
        }
    }
}

/// How a scene file's coordinates become the world's (z up, metres): which of its axes points
/// up (none given: the format's default, `UpAxis::default_for`) and how many metres one of
/// its units is (`[scene] up_axis` and `unit_m` of synth and run configs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SceneFrame {
    pub up: Option<UpAxis>,
    pub unit_m: f64,
}

impl Default for SceneFrame {
    fn default() -> Self {
        Self {
            up: None,
            unit_m: 1.0,
        }
    }
}

impl SceneFrame {
    /// Smallest and largest `unit_m` taken: a micrometre to a kilometre per unit.
    pub(crate) const UNIT_M_RANGE: (f64, f64) = (1e-6, 1e3);

    /// The frame of a file whose up axis and unit are given where given (a config's keys, a
    /// command's flags); a unit outside [`Self::UNIT_M_RANGE`] (or not finite) is the message
    /// returned.
    pub fn new(up: Option<UpAxis>, unit_m: Option<f64>) -> Result<Self, String> {
        let unit_m = unit_m.unwrap_or(1.0);
        let (lo, hi) = Self::UNIT_M_RANGE;
        if !(unit_m.is_finite() && (lo..=hi).contains(&unit_m)) {
            return Err(format!(
                "expected metres per unit of the scene file between {lo} and {hi} (0.01 for centimetres, 0.001 for millimetres), got {unit_m}"
            ));
        }
        Ok(Self { up, unit_m })
    }

    /// The file's up axis: the one given, else the format's default.
    pub(crate) fn up_for(&self, path: &Path) -> UpAxis {
        self.up.unwrap_or_else(|| UpAxis::default_for(path))
    }

    /// Whether the file is read as its format says (default up axis, metres): what plans
    /// leave out of their serialised form, so that earlier plans read the same.
    pub(crate) fn is_default(&self) -> bool {
        *self == Self::default()
    }

    fn to_world(self, up: UpAxis, p: [f64; 3]) -> Vec3 {
        up.to_z_up(p) * self.unit_m
    }
}

/// A scene that could not be used, with the file named.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("scene {path}: unsupported format `.{ext}` (supported: .glb, .gltf, .obj, .ply)")]
    Unsupported { path: PathBuf, ext: String },
    #[error("scene {path}: cannot read ({message})")]
    Read { path: PathBuf, message: String },
    #[error("scene {path}: no triangles (empty scene)")]
    Empty { path: PathBuf },
    #[error("scene {path}: object `{object}` has a non-finite vertex (index {index})")]
    NonFinite {
        path: PathBuf,
        object: String,
        index: usize,
    },
    #[error("scene {path}: object `{object}` has face index {index} but only {count} vertices")]
    BadIndex {
        path: PathBuf,
        object: String,
        index: u32,
        count: usize,
    },
    #[error("scene {path}: no floor found (no upward-facing horizontal surface); is the up axis right? (give the other one: `[scene] up_axis = \"y\"` or `\"z\"` in a config, `--up y|z` on the command line)")]
    NoFloor { path: PathBuf },
    #[error("scene {path}: no walkable cell (floor at {floor_z_m:.2} m is covered everywhere between {lo:.2} and {hi:.2} m){hint}")]
    NoWalkable {
        path: PathBuf,
        floor_z_m: f64,
        lo: f64,
        hi: f64,
        /// What to check, when the scene's size or the floor asked for suggests it.
        hint: String,
    },
    #[error("scene {path}: `[scene] floor_z_m` = {floor_z_m} (--floor-z-m) is outside the scene's heights ({lo:.2} to {hi:.2} m); expected the height of one of its floors")]
    FloorOutside {
        path: PathBuf,
        floor_z_m: f64,
        lo: f64,
        hi: f64,
    },
    #[error(
        "scene {path}: a walkable map of {nx} × {ny} cells of {cell_m} m would need about {gb:.1} GB; \
         at most {} cells are allowed: use a larger cell size, or, if the file is not in metres, \
         give its unit (`[scene] unit_m = 0.01` for centimetres, 0.001 for millimetres; `--unit-m`)",
        super::walkable::MAX_MAP_CELLS
    )]
    MapTooLarge {
        path: PathBuf,
        nx: f64,
        ny: f64,
        cell_m: f64,
        gb: f64,
    },
    #[error("scene {path}: {message}; use a larger cell size")]
    MapOutOfMemory { path: PathBuf, message: String },
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

/// Loads a scene file (format from the extension) into world space, z up, metres, its
/// coordinates read as `frame` says.
pub fn load_scene(path: &Path, frame: SceneFrame) -> Result<SceneMesh, SceneError> {
    let up = frame.up_for(path);
    let read_err = |message: String| SceneError::Read {
        path: path.to_owned(),
        message,
    };
    if !path.is_file() {
        return Err(read_err("file not found".into()));
    }
    // What the reader said, and what the file should have been: a damaged or mislabelled file
    // says so rather than only quoting the parser.
    let not_a = |format: &'static str| {
        move |message: String| {
            read_err(format!(
                "not a valid {format} file: {message}; check that the file is complete and is {format} (the format follows the extension)"
            ))
        }
    };
    let (parts, face_parts) = match extension(path).as_str() {
        "glb" | "gltf" => (read_gltf(path).map_err(not_a("glTF"))?, None),
        "obj" => (read_obj(path).map_err(not_a("Wavefront OBJ"))?, None),
        "ply" => read_ply(path).map_err(not_a("PLY"))?,
        ext => {
            return Err(SceneError::Unsupported {
                path: path.to_owned(),
                ext: ext.to_owned(),
            })
        }
    };
    let labels = match &face_parts {
        Some((_, PlyIds::Objects)) => replica_labels(path)?,
        Some((_, PlyIds::Nyu40Classes)) => (0..)
            .zip(NYU40_CLASSES)
            .map(|(id, name)| (id, name.to_owned()))
            .collect(),
        None => Default::default(),
    };
    let mut mesh = SceneMesh::default();
    // Object index of each part (none when it made no triangle).
    let mut part_object = Vec::with_capacity(parts.len());
    for part in parts {
        part_object.push(u32::MAX);
        if let Some(i) = part
            .positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(SceneError::NonFinite {
                path: path.to_owned(),
                object: part.name,
                index: i,
            });
        }
        if let Some(&bad) = part
            .triangles
            .iter()
            .flatten()
            .find(|&&i| i as usize >= part.positions.len())
        {
            return Err(SceneError::BadIndex {
                path: path.to_owned(),
                object: part.name,
                index: bad,
                count: part.positions.len(),
            });
        }
        if part.triangles.is_empty() {
            continue;
        }
        let verts: Vec<Vec3> = part
            .positions
            .iter()
            .map(|&p| frame.to_world(up, p))
            .collect();
        let id = mesh.add_object(part.name, &verts, &part.triangles);
        *part_object.last_mut().expect("pushed above") = id.0 - 1;
        let object = &mut mesh.objects[id.0 as usize - 1];
        object.textured = part.textured;
        object.see_through = part.see_through;
        if let Some(file_id) = part.file_id {
            object.label = labels.get(&file_id).cloned();
        }
    }
    mesh.file_face_objects = face_parts.map(|(faces, _)| {
        faces
            .iter()
            .map(|&p| part_object.get(p as usize).copied().unwrap_or(u32::MAX))
            .collect()
    });
    if mesh.triangles.is_empty() {
        return Err(SceneError::Empty {
            path: path.to_owned(),
        });
    }
    Ok(mesh)
}

/// One object as read from a file, in file coordinates.
struct Part {
    name: String,
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// The object id the file gives it (a PLY's `object_id`), when it gives one.
    file_id: Option<i64>,
    /// Its surface has an image texture or vertex colours ([`crate::scene::SceneObject::textured`]).
    textured: bool,
    /// A material lets light through ([`crate::scene::SceneObject::see_through`]).
    see_through: bool,
}

impl Part {
    /// A part named `name` with no geometry yet, untextured, opaque, without a file id.
    fn empty(name: String) -> Part {
        Part {
            name,
            positions: Vec::new(),
            triangles: Vec::new(),
            file_id: None,
            textured: false,
            see_through: false,
        }
    }
}

/// How far above a scene's lowest point the floor found may lie before it is taken for a
/// scene on its side (m): more than a floor slab or a few steps down.
pub(crate) const FLOOR_HIGH_ABOVE_LOWEST_M: f64 = 1.0;

/// How far below a scene's lowest point `floor_z_m` may be asked for (m): a floor is in the
/// scene, give or take a slab.
const FLOOR_BELOW_SCENE_M: f64 = 0.5;

/// A scene less than this wide at its widest (m) is too small to walk in: most often a file
/// not in metres read as if it were.
pub(crate) const SMALL_SCENE_M: f64 = 1.5;

/// What to say of a scene whose bounds are less than [`SMALL_SCENE_M`] wide at the widest.
fn small_scene((lo, hi): (Vec3, Vec3)) -> Option<String> {
    let (w, d) = (hi.x - lo.x, hi.y - lo.y);
    (w.max(d) < SMALL_SCENE_M).then(|| {
        format!(
            "the scene is only {w:.2} × {d:.2} m across: if the file is not in metres, give its unit (`[scene] unit_m`, --unit-m; 0.01 for centimetres, 0.001 for millimetres)"
        )
    })
}

/// A scene taller than [`TALLER_THAN_WIDE`] times its narrowest horizontal extent, and than
/// [`TALLER_THAN_WIDE_M`], is taken for one on its side (a dwelling is wider than it is tall:
/// the shipped apartment read z up is 10.2 m tall and 2.5 m across).
pub(crate) const TALLER_THAN_WIDE: f64 = 1.5;
/// See [`TALLER_THAN_WIDE`] (m).
pub(crate) const TALLER_THAN_WIDE_M: f64 = 4.0;

/// A warning for a scene most likely read in the wrong frame, naming the file and what to
/// give: too small to walk in ([`SMALL_SCENE_M`]: the unit), or on its side (walked on a
/// wall's end or a table's side): its floor lies more than
/// [`FLOOR_HIGH_ABOVE_LOWEST_M`] above the scene's lowest point when no storey was asked for,
/// or the scene is much taller than wide ([`TALLER_THAN_WIDE`]); none otherwise.
pub(crate) fn scene_frame_warning(
    mesh: &SceneMesh,
    map: &super::WalkableMap,
    path: &Path,
) -> Option<String> {
    let (lo, hi) = mesh.bounds()?;
    let above_m = map.floor_z_m - lo.z;
    if let Some(small) = small_scene((lo, hi)) {
        return Some(format!("warning: scene {}: {small}", path.display()));
    }
    let what = if map.settings.floor_z_m.is_none() && above_m > FLOOR_HIGH_ABOVE_LOWEST_M {
        format!("the floor found lies {above_m:.2} m above the scene's lowest point")
    } else {
        let (tall, narrow) = (hi.z - lo.z, (hi.x - lo.x).min(hi.y - lo.y));
        if tall > TALLER_THAN_WIDE_M.max(TALLER_THAN_WIDE * narrow) {
            format!("the scene is {tall:.2} m tall and {narrow:.2} m across at its narrowest")
        } else {
            return None;
        }
    };
    Some(format!(
        "warning: scene {}: {what}; if the scene lies on its side, give its up axis (`[scene] up_axis`, --up y|z) and unit (`[scene] unit_m`, --unit-m)",
        path.display()
    ))
}

/// Builds the walkable map of a loaded scene, naming the file in errors.
pub fn walkable_map(
    mesh: &SceneMesh,
    path: &Path,
    settings: super::WalkableSettings,
) -> Result<super::WalkableMap, SceneError> {
    use super::walkable::WalkableError;
    let bounds = mesh.bounds();
    if let (Some(z), Some((lo, hi))) = (settings.floor_z_m, bounds) {
        if !(lo.z - FLOOR_BELOW_SCENE_M..=hi.z).contains(&z) {
            return Err(SceneError::FloorOutside {
                path: path.to_owned(),
                floor_z_m: z,
                lo: lo.z,
                hi: hi.z,
            });
        }
    }
    super::WalkableMap::build(mesh, settings).map_err(|e| match e {
        WalkableError::NoFloor => SceneError::NoFloor {
            path: path.to_owned(),
        },
        WalkableError::NoWalkable { floor_z_m, lo, hi } => SceneError::NoWalkable {
            path: path.to_owned(),
            floor_z_m,
            lo,
            hi,
            hint: match (settings.floor_z_m, bounds) {
                (Some(_), _) => "; it is the floor asked for with `[scene] floor_z_m` (--floor-z-m): is that one of the scene's floors?".into(),
                (None, Some(b)) => small_scene(b).map(|s| format!("; {s}")).unwrap_or_default(),
                (None, None) => String::new(),
            },
        },
        WalkableError::TooManyCells { nx, ny, cell_m } => SceneError::MapTooLarge {
            path: path.to_owned(),
            nx,
            ny,
            cell_m,
            gb: nx * ny * super::walkable::MAP_BYTES_PER_CELL / 1e9,
        },
        WalkableError::OutOfMemory(message) => SceneError::MapOutOfMemory {
            path: path.to_owned(),
            message,
        },
    })
}
