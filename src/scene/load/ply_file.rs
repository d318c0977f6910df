//! Reading PLY files (`ply-rs-bw`): one part, or one per object id (Replica) or class label
//! (ScanNet), with the part of each file face; the class names beside a Replica scan.

use std::path::Path;

use super::{Part, SceneError};

/// Class names of a Replica scan's object ids, from the `info_semantic.json` beside it
/// (`objects: [{"id", "class_name"}, …]`); none when there is no such file.
pub(super) fn replica_labels(
    path: &Path,
) -> Result<std::collections::HashMap<i64, String>, SceneError> {
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
pub(super) enum PlyIds {
    Objects,
    Nyu40Classes,
}

/// The 40 classes of NYU Depth v2 as ScanNet's `label` numbers them (1–40; 0: unannotated),
/// spelled as ScanNet's label tables spell them.
pub(super) const NYU40_CLASSES: [&str; 41] = [
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
pub(super) fn read_ply(path: &Path) -> Result<(Vec<Part>, Option<(Vec<u32>, PlyIds)>), String> {
    let (header, verts, faces) = read_ply_elements(path)?;
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
    let (parts, face_part) = ply_parts_by_id(
        name,
        positions,
        triangles,
        face_ids,
        triangle_face,
        coloured,
    )?;
    Ok((parts, Some((face_part, kind))))
}

/// A PLY file's header and its `vertex` and `face` elements (any other element read past).
fn read_ply_elements(
    path: &Path,
) -> Result<(ply_rs_bw::ply::Header, Option<Vec<PlyVertex>>, Vec<PlyFace>), String> {
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
    Ok((header, verts, faces))
}

/// One part per id, ascending, each with the vertices its triangles use; with the part of
/// each file face.
fn ply_parts_by_id(
    name: String,
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    face_ids: Vec<i64>,
    triangle_face: Vec<u32>,
    coloured: bool,
) -> Result<(Vec<Part>, Vec<u32>), String> {
    let mut ids: Vec<i64> = face_ids.clone();
    ids.sort_unstable();
    ids.dedup();
    let part_of = |id: i64| ids.binary_search(&id).expect("every id is listed") as u32;
    let face_part: Vec<u32> = face_ids.iter().map(|&id| part_of(id)).collect();
    let mut parts: Vec<Part> = ids
        .iter()
        .map(|&id| Part {
            file_id: Some(id),
            textured: coloured,
            ..Part::empty(split_name(&name, id))
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
    Ok((parts, face_part))
}
