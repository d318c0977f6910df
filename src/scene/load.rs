//! Reading scene files: glTF/GLB (`gltf`), OBJ (`tobj`), PLY (`ply-rs-bw`), into a
//! [`SceneMesh`] in metres with z up.
//!
//! Up axis: glTF is y up by specification, so `.gltf`/`.glb` default to [`UpAxis::Y`]; OBJ and
//! PLY default to [`UpAxis::Z`] (scanned scenes mostly are). A y-up point `(x, y, z)` becomes
//! `(x, −z, y)` in the z-up world. Units: metres by default (glTF's by specification); a file
//! in other units is scaled by its [`SceneFrame::unit_m`] (0.01 for centimetres).

use std::path::{Path, PathBuf};

use super::mesh::SceneMesh;
use crate::math::Vec3;

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
    pub fn from_name(name: &str) -> Option<UpAxis> {
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
    pub const UNIT_M_RANGE: (f64, f64) = (1e-6, 1e3);

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
    pub fn up_for(&self, path: &Path) -> UpAxis {
        self.up.unwrap_or_else(|| UpAxis::default_for(path))
    }

    /// Whether the file is read as its format says (default up axis, metres): what plans
    /// leave out of their serialised form, so that earlier plans read the same.
    pub fn is_default(&self) -> bool {
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
    /// Its surface has an image texture or vertex colours ([`SceneObject::textured`]).
    textured: bool,
    /// A material lets light through ([`SceneObject::see_through`]).
    see_through: bool,
}

/// Class names of a Replica scan's object ids, from the `info_semantic.json` beside it
/// (`objects: [{"id", "class_name"}, …]`); none when there is no such file.
fn replica_labels(path: &Path) -> Result<std::collections::HashMap<i64, String>, SceneError> {
    let file = path.with_file_name("info_semantic.json");
    let Ok(text) = std::fs::read_to_string(&file) else {
        return Ok(Default::default());
    };
    let bad = |message: String| {
        SceneError::Read {
        path: file.clone(),
        message: format!("{message}; expected Replica's `objects: [{{\"id\": N, \"class_name\": \"…\"}}]` (labels of the scan's object ids)"),
    }
    };
    let doc: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    let objects = doc["objects"]
        .as_array()
        .ok_or_else(|| bad("no `objects` list".into()))?;
    objects
        .iter()
        .enumerate()
        .filter(|(_, o)| !o["class_name"].is_null())
        .map(
            |(k, o)| match (o["id"].as_i64(), o["class_name"].as_str()) {
                (Some(id), Some(name)) => Ok((id, name.to_owned())),
                _ => Err(bad(format!(
                    "objects[{k}]: no integer `id` or string `class_name`"
                ))),
            },
        )
        .collect()
}

fn read_gltf(path: &Path) -> Result<Vec<Part>, String> {
    crate::parser_guard::catch_parser_panic(|| read_gltf_parts(path))
        .map_err(|e| format!("not a valid glTF file ({e})"))?
}

fn read_gltf_parts(path: &Path) -> Result<Vec<Part>, String> {
    let gltf = gltf::Gltf::open(path).map_err(|e| e.to_string())?;
    let buffers = gltf::import_buffers(&gltf.document, path.parent(), gltf.blob.clone())
        .map_err(|e| e.to_string())?;
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or("the file has no scene")?;
    let mut parts = Vec::new();
    let mut stack: Vec<(gltf::Node, glam::DMat4)> =
        scene.nodes().map(|n| (n, glam::DMat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        stack.extend(node.children().map(|c| (c, world)));
        let Some(mesh) = node.mesh() else { continue };
        let name = node
            .name()
            .or(mesh.name())
            .map(str::to_owned)
            .unwrap_or_else(|| format!("node_{}", node.index()));
        let mut part = Part {
            name,
            positions: Vec::new(),
            triangles: Vec::new(),
            file_id: None,
            textured: false,
            see_through: false,
        };
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            part.textured |= prim
                .material()
                .pbr_metallic_roughness()
                .base_color_texture()
                .is_some()
                || prim.get(&gltf::Semantic::Colors(0)).is_some();
            part.see_through |= prim.material().alpha_mode() != gltf::material::AlphaMode::Opaque;
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(pos) = reader.read_positions() else {
                continue;
            };
            let base = part.positions.len() as u32;
            part.positions.extend(pos.map(|p| {
                world
                    .transform_point3(glam::Vec3::from(p).as_dvec3())
                    .to_array()
            }));
            let n = part.positions.len() as u32 - base;
            let idx: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..n).collect(),
            };
            part.triangles.extend(
                idx.chunks_exact(3)
                    .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
            );
        }
        parts.push(part);
    }
    parts.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(parts)
}

/// tobj's name for faces that come before any `o` or `g` line.
const TOBJ_UNNAMED: &str = "unnamed_object";

/// An OBJ's objects and groups (`o`, `g`), each one part; the pieces tobj splits off where
/// the material changes (`usemtl`) join their object again, in order of first appearance, so
/// that parts are named as Blender's importer names its objects (one per object or group).
/// Faces before any `o` or `g` line (a file without them: all its faces) are one part named
/// after the file, as Blender names that object.
fn read_obj(path: &Path) -> Result<Vec<Part>, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, materials) = tobj::load_obj(path, &opts).map_err(|e| e.to_string())?;
    // A missing or unreadable MTL leaves the faces untextured, as Blender's importer does.
    let materials = materials.unwrap_or_default();
    let leading = obj_faces_before_any_object(path)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "obj".into());
    let mut parts: Vec<Part> = Vec::new();
    let mut index = std::collections::HashMap::new();
    for m in models {
        let name = match (&leading, m.name.as_str()) {
            (Some(named_unnamed), TOBJ_UNNAMED) if !named_unnamed => stem.clone(),
            _ => m.name,
        };
        let k = *index.entry(name.clone()).or_insert_with(|| {
            parts.push(Part {
                name,
                positions: Vec::new(),
                triangles: Vec::new(),
                file_id: None,
                textured: false,
                see_through: false,
            });
            parts.len() - 1
        });
        let part = &mut parts[k];
        if let Some(mat) = m.mesh.material_id.and_then(|i| materials.get(i)) {
            part.textured |= mat
                .diffuse_texture
                .as_deref()
                .is_some_and(|t| !t.is_empty());
            part.see_through |=
                mat.dissolve.is_some_and(|d| d < 1.0) || mat.dissolve_texture.is_some();
        }
        let base = part.positions.len() as u32;
        part.positions.extend(
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]),
        );
        part.triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]].map(|i| i.saturating_add(base))),
        );
    }
    Ok(parts)
}

/// Whether an OBJ has faces before its first `o` or `g` line (`Some`), and then whether one of
/// its `o`/`g` lines is itself named tobj's [`TOBJ_UNNAMED`] (then both are one part, as tobj
/// reads them).
fn obj_faces_before_any_object(path: &Path) -> Result<Option<bool>, String> {
    use std::io::BufRead;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut leading = false;
    let mut named_unnamed = false;
    for line in std::io::BufReader::new(file).split(b'\n') {
        let line = line.map_err(|e| e.to_string())?;
        let line = line.trim_ascii_start();
        match line.first() {
            // (An `o`/`g` line before any face has returned already.)
            Some(b'f') if line.get(1).is_some_and(u8::is_ascii_whitespace) => leading = true,
            Some(b'o' | b'g') if line.get(1).is_none_or(u8::is_ascii_whitespace) => {
                if !leading {
                    return Ok(None);
                }
                if line[1..].trim_ascii() == TOBJ_UNNAMED.as_bytes() {
                    named_unnamed = true;
                }
            }
            _ => {}
        }
    }
    Ok(leading.then_some(named_unnamed))
}

/// Longest object name Blender keeps (bytes of UTF-8); it cuts longer ones.
pub(crate) const BLENDER_NAME_BYTES: usize = 63;

/// `<stem>_<id>`, the stem cut (at a character boundary) so that the whole fits in
/// [`BLENDER_NAME_BYTES`]: the id that tells a scan's objects apart survives in Blender.
fn split_name(stem: &str, id: i64) -> String {
    let suffix = format!("_{id}");
    let mut end = BLENDER_NAME_BYTES
        .saturating_sub(suffix.len())
        .min(stem.len());
    while !stem.is_char_boundary(end) {
        end -= 1;
    }
    format!("{}{suffix}", &stem[..end])
}

/// A number of any PLY scalar type.
fn ply_number(p: &ply_rs_bw::ply::Property) -> Option<f64> {
    use ply_rs_bw::ply::Property;
    match *p {
        Property::Float(v) => Some(v as f64),
        Property::Double(v) => Some(v),
        Property::Int(v) => Some(v as f64),
        Property::UInt(v) => Some(v as f64),
        Property::Short(v) => Some(v as f64),
        Property::UShort(v) => Some(v as f64),
        Property::Char(v) => Some(v as f64),
        Property::UChar(v) => Some(v as f64),
        _ => None,
    }
}

/// A PLY vertex as read: its position and object id (`object_id` or `objectId`), each none
/// when absent or not a number. Typed elements keep a scan of 10⁶ triangles in tens of MB
/// instead of a map of properties per element.
#[derive(Default)]
struct PlyVertex {
    xyz: [Option<f64>; 3],
    id: Option<Option<f64>>,
    /// ScanNet's `label`: the NYU40 class of the vertex.
    class: Option<Option<f64>>,
}

impl ply_rs_bw::ply::PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(
        &mut self,
        key: &str,
        property: ply_rs_bw::ply::Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        match key {
            "x" => self.xyz[0] = ply_number(&property),
            "y" => self.xyz[1] = ply_number(&property),
            "z" => self.xyz[2] = ply_number(&property),
            "object_id" | "objectId" => self.id = Some(ply_number(&property)),
            "label" => self.class = Some(ply_number(&property)),
            _ => return ply_rs_bw::ply::PropertyAccessResult::Ignored,
        }
        ply_rs_bw::ply::PropertyAccessResult::Set
    }
}

/// What a PLY's per-face ids are: object ids (Replica's `object_id`, a scanner's `objectId`;
/// classes from `info_semantic.json` beside the file) or classes (ScanNet's vertex `label`,
/// NYU40 ids).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PlyIds {
    Objects,
    Nyu40Classes,
}

/// The 40 classes of NYU Depth v2 as ScanNet's `label` numbers them (1–40; 0: unannotated),
/// spelled as ScanNet's label tables spell them.
const NYU40_CLASSES: [&str; 41] = [
    "unannotated",
    "wall",
    "floor",
    "cabinet",
    "bed",
    "chair",
    "sofa",
    "table",
    "door",
    "window",
    "bookshelf",
    "picture",
    "counter",
    "blinds",
    "desk",
    "shelves",
    "curtain",
    "dresser",
    "pillow",
    "mirror",
    "floor mat",
    "clothes",
    "ceiling",
    "books",
    "refridgerator",
    "television",
    "paper",
    "towel",
    "shower curtain",
    "box",
    "whiteboard",
    "person",
    "night stand",
    "toilet",
    "sink",
    "lamp",
    "bathtub",
    "bag",
    "otherstructure",
    "otherfurniture",
    "otherprop",
];

/// A PLY face as read: its vertex indices (none when the list is missing or not of integers)
/// and its `object_id`.
#[derive(Default)]
struct PlyFace {
    indices: Option<Vec<u32>>,
    id: Option<Option<f64>>,
}

impl ply_rs_bw::ply::PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(
        &mut self,
        key: &str,
        property: ply_rs_bw::ply::Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::Property;
        match key {
            "vertex_indices" | "vertex_index" => {
                self.indices = match property {
                    Property::ListInt(v) => Some(v.iter().map(|&i| i.max(0) as u32).collect()),
                    Property::ListUInt(v) => Some(v),
                    Property::ListUChar(v) => Some(v.iter().map(|&i| i as u32).collect()),
                    Property::ListChar(v) => Some(v.iter().map(|&i| i.max(0) as u32).collect()),
                    Property::ListShort(v) => Some(v.iter().map(|&i| i.max(0) as u32).collect()),
                    Property::ListUShort(v) => Some(v.iter().map(|&i| i as u32).collect()),
                    _ => None,
                }
            }
            "object_id" => self.id = Some(ply_number(&property)),
            _ => return ply_rs_bw::ply::PropertyAccessResult::Ignored,
        }
        ply_rs_bw::ply::PropertyAccessResult::Set
    }
}

/// An element egogen does not read (edges, materials, …), skipped.
struct PlySkipped;

impl ply_rs_bw::ply::PropertyAccess for PlySkipped {
    fn new() -> Self {
        Self
    }
}

/// A PLY file as one part, or, when its faces carry an `object_id` (Replica) or its vertices
/// an `object_id` / `objectId` or, without those, ScanNet's class `label` (a face takes its
/// first vertex's), one part per id in ascending order, named `<file stem>_<id>`, with the
/// part of each face of the file and what the ids are.
#[allow(clippy::type_complexity)]
fn read_ply(path: &Path) -> Result<(Vec<Part>, Option<(Vec<u32>, PlyIds)>), String> {
    use ply_rs_bw::parser::{Parser, Reader};
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut reader = Reader::new(std::io::BufReader::new(file));
    let header = Parser::<PlySkipped>::new()
        .read_header(&mut reader)
        .map_err(|e| e.to_string())?;
    let (mut verts, mut faces) = (None, Vec::new());
    for element in header.elements.values() {
        match element.name.as_str() {
            "vertex" => {
                verts = Some(
                    Parser::<PlyVertex>::new()
                        .read_payload_for_element(&mut reader, element, &header)
                        .map_err(|e| e.to_string())?,
                )
            }
            "face" => {
                faces = Parser::<PlyFace>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| e.to_string())?
            }
            _ => {
                Parser::<PlySkipped>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| e.to_string())?;
            }
        }
    }
    let verts = verts.ok_or("no `vertex` element")?;
    let coloured = header.elements.get("vertex").is_some_and(|v| {
        ["red", "green", "blue"]
            .iter()
            .all(|c| v.properties.contains_key(*c))
    });
    let positions = verts
        .iter()
        .enumerate()
        .map(|(i, v)| match v.xyz {
            [Some(x), Some(y), Some(z)] => Ok([x, y, z]),
            _ => Err(format!("vertex {i} lacks numeric x, y, z")),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let whole = |v: f64| (v.fract() == 0.0 && v.abs() < 9e15).then_some(v as i64);
    let vertex_ids = verts.first().is_some_and(|v| v.id.is_some());
    let vertex_classes = !vertex_ids && verts.first().is_some_and(|v| v.class.is_some());
    let kind = match faces.first().is_some_and(|f| f.id.is_some()) || !vertex_classes {
        true => PlyIds::Objects,
        false => PlyIds::Nyu40Classes,
    };
    let mut triangles = Vec::new();
    // Each face's object id and the file face of each triangle, when ids are given.
    let mut face_ids: Vec<i64> = Vec::new();
    let mut triangle_face: Vec<u32> = Vec::new();
    for (fi, face) in faces.iter().enumerate() {
        let idx = face.indices.as_ref().ok_or(format!(
            "face {fi} lacks vertex_indices (a list of integers)"
        ))?;
        let id = match (face.id, vertex_ids) {
            (Some(id), _) => Some(
                id.and_then(whole)
                    .ok_or(format!("face {fi}: `object_id` is not a whole number"))?,
            ),
            (None, true) => match idx.first().and_then(|&v| verts.get(v as usize)) {
                Some(v) => Some(v.id.flatten().and_then(whole).ok_or(format!(
                    "vertex {}: its object id is not a whole number",
                    idx[0]
                ))?),
                None => Some(-1),
            },
            (None, false) if vertex_classes => {
                match idx.first().and_then(|&v| verts.get(v as usize)) {
                    Some(v) => Some(v.class.flatten().and_then(whole).ok_or(format!(
                        "vertex {}: its `label` is not a whole number",
                        idx[0]
                    ))?),
                    None => Some(-1),
                }
            }
            (None, false) => None,
        };
        if let Some(id) = id {
            face_ids.push(id);
        }
        for k in 1..idx.len().saturating_sub(1) {
            triangles.push([idx[0], idx[k], idx[k + 1]]);
            triangle_face.push(fi as u32);
        }
    }
    let face_count = faces.len();
    drop(verts);
    drop(faces);
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ply".into());
    if face_ids.len() != face_count || face_count == 0 {
        return Ok((
            vec![Part {
                name,
                positions,
                triangles,
                file_id: None,
                textured: coloured,
                see_through: false,
            }],
            None,
        ));
    }
    // One part per id, ascending, each with the vertices its triangles use.
    let mut ids: Vec<i64> = face_ids.clone();
    ids.sort_unstable();
    ids.dedup();
    let part_of = |id: i64| ids.binary_search(&id).expect("every id is listed") as u32;
    let face_part: Vec<u32> = face_ids.iter().map(|&id| part_of(id)).collect();
    let mut parts: Vec<Part> = ids
        .iter()
        .map(|&id| Part {
            name: split_name(&name, id),
            positions: Vec::new(),
            triangles: Vec::new(),
            file_id: Some(id),
            textured: coloured,
            see_through: false,
        })
        .collect();
    let mut local: Vec<(u32, u32)> = vec![(u32::MAX, 0); positions.len()];
    // Part by part (stable: each part's triangles in file order), so a vertex is copied once
    // into each part that uses it.
    let mut order: Vec<usize> = (0..triangles.len()).collect();
    order.sort_by_key(|&t| face_part[triangle_face[t] as usize]);
    for t in order {
        let (t, fi) = (&triangles[t], triangle_face[t]);
        let p = face_part[fi as usize];
        let part = &mut parts[p as usize];
        let mut out = [0u32; 3];
        for (o, &v) in out.iter_mut().zip(t) {
            let Some(slot) = local.get_mut(v as usize) else {
                return Err(format!(
                    "face {fi}: vertex index {v} beyond the {} vertices",
                    positions.len()
                ));
            };
            if slot.0 != p {
                *slot = (p, part.positions.len() as u32);
                part.positions.push(positions[v as usize]);
            }
            *o = slot.1;
        }
        part.triangles.push(out);
    }
    Ok((parts, Some((face_part, kind))))
}

/// How far above a scene's lowest point the floor found may lie before it is taken for a
/// scene on its side (m): more than a floor slab or a few steps down.
pub const FLOOR_HIGH_ABOVE_LOWEST_M: f64 = 1.0;

/// How far below a scene's lowest point `floor_z_m` may be asked for (m): a floor is in the
/// scene, give or take a slab.
const FLOOR_BELOW_SCENE_M: f64 = 0.5;

/// A scene less than this wide at its widest (m) is too small to walk in: most often a file
/// not in metres read as if it were.
pub const SMALL_SCENE_M: f64 = 1.5;

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
pub const TALLER_THAN_WIDE: f64 = 1.5;
/// See [`TALLER_THAN_WIDE`] (m).
pub const TALLER_THAN_WIDE_M: f64 = 4.0;

/// A warning for a scene most likely read in the wrong frame, naming the file and what to
/// give: too small to walk in ([`SMALL_SCENE_M`]: the unit), or on its side (walked on a
/// wall's end or a table's side): its floor lies more than
/// [`FLOOR_HIGH_ABOVE_LOWEST_M`] above the scene's lowest point when no storey was asked for,
/// or the scene is much taller than wide ([`TALLER_THAN_WIDE`]); none otherwise.
pub fn scene_frame_warning(
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
