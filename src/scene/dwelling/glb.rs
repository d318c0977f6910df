//! Writes a dwelling as one binary glTF: a node per object (named as the scene mesh names it),
//! the generated architecture as box meshes with plain materials, each catalogue model's mesh,
//! materials and textures copied once from its GLB (indices shifted) and shared by every node
//! that places it (turned and moved by the node's transform); a picture's painting as its own
//! PNG texture on its front. y up, as glTF is.

use serde_json::{json, Map, Value};

use super::{catalogue::Catalogue, Dwelling, DwellingError};

/// The look of a generated object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Look {
    Wall,
    Floor,
    Ceiling,
    Frame,
    Leaf,
    Lamp,
}

impl Look {
    const ALL: [Look; 6] = [
        Look::Wall,
        Look::Floor,
        Look::Ceiling,
        Look::Frame,
        Look::Leaf,
        Look::Lamp,
    ];

    fn material(self) -> Value {
        let (name, colour, roughness) = match self {
            Look::Wall => ("wall_paint", [0.82, 0.80, 0.76], 0.9),
            Look::Floor => ("floor_wood", [0.45, 0.32, 0.20], 0.6),
            Look::Ceiling => ("ceiling_paint", [0.90, 0.90, 0.88], 0.95),
            Look::Frame => ("frame_paint", [0.93, 0.93, 0.92], 0.5),
            Look::Leaf => ("door_wood", [0.62, 0.48, 0.33], 0.55),
            Look::Lamp => ("lamp_glow", [1.0, 0.97, 0.9], 0.5),
        };
        let mut m = json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [colour[0], colour[1], colour[2], 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": roughness,
            },
        });
        if self == Look::Lamp {
            m["emissiveFactor"] = json!([1.0, 0.97, 0.9]);
            m["extensions"] =
                json!({ "KHR_materials_emissive_strength": { "emissiveStrength": 30.0 } });
        }
        m
    }
}

/// The growing file: its binary chunk and JSON arrays.
#[derive(Default)]
struct Out {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    textures: Vec<Value>,
    images: Vec<Value>,
    samplers: Vec<Value>,
    nodes: Vec<Value>,
    /// The sampler every painting shares, once one is written.
    painting_sampler: Option<usize>,
}

impl Out {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        pad(&mut self.bin, 0);
        let mut v = json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// An accessor of `N`-vectors of floats (positions, normals, texture coordinates).
    fn floats<const N: usize>(&mut self, data: &[[f32; N]], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes, Some(34962));
        let mut a = json!({ "bufferView": view, "componentType": 5126, "count": data.len(), "type": format!("VEC{N}") });
        if with_bounds {
            let lo = data.iter().fold([f32::INFINITY; N], |a, v| {
                std::array::from_fn(|k| a[k].min(v[k]))
            });
            let hi = data.iter().fold([f32::NEG_INFINITY; N], |a, v| {
                std::array::from_fn(|k| a[k].max(v[k]))
            });
            a["min"] = json!(lo.as_slice());
            a["max"] = json!(hi.as_slice());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// A material showing a PNG (a picture's painting): the image in the binary chunk, one
    /// linear sampler shared by every painting; returns the material's index.
    fn painting(&mut self, name: &str, png: &[u8]) -> usize {
        let view = self.view(png, None);
        self.images
            .push(json!({ "bufferView": view, "mimeType": "image/png" }));
        let sampler = *self.painting_sampler.get_or_insert_with(|| {
            self.samplers.push(painting_sampler());
            self.samplers.len() - 1
        });
        self.textures
            .push(json!({ "source": self.images.len() - 1, "sampler": sampler }));
        self.materials.push(json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": self.textures.len() - 1 },
                "metallicFactor": 0.0,
                "roughnessFactor": 0.6,
            },
        }));
        self.materials.len() - 1
    }

    fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(34963));
        self.accessors.push(json!({ "bufferView": view, "componentType": 5125, "count": data.len(), "type": "SCALAR" }));
        self.accessors.len() - 1
    }

    /// Copies a model GLB's meshes, materials, textures and images in; returns the index of
    /// its (first) mesh.
    fn model(&mut self, glb: &[u8]) -> Result<usize, String> {
        let g = gltf::Gltf::from_slice(glb).map_err(|e| e.to_string())?;
        let blob = g.blob.clone().ok_or("no binary chunk")?;
        let root = serde_json::to_value(g.document.into_json()).map_err(|e| e.to_string())?;
        let arr = |k: &str| {
            root.get(k)
                .and_then(Value::as_array)
                .cloned()
                .unwrap_or_default()
        };
        pad(&mut self.bin, 0);
        let (bin0, view0, acc0) = (self.bin.len(), self.views.len(), self.accessors.len());
        let (mat0, tex0, img0, smp0, mesh0) = (
            self.materials.len(),
            self.textures.len(),
            self.images.len(),
            self.samplers.len(),
            self.meshes.len(),
        );
        self.bin.extend_from_slice(&blob);
        let shift = |v: &mut Value, key: &str, by: usize| {
            if let Some(i) = v.get(key).and_then(Value::as_u64) {
                v[key] = json!(i as usize + by);
            }
        };
        for mut v in arr("bufferViews") {
            v["buffer"] = json!(0);
            let offset = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
            v["byteOffset"] = json!(offset + bin0);
            self.views.push(v);
        }
        for mut a in arr("accessors") {
            shift(&mut a, "bufferView", view0);
            self.accessors.push(a);
        }
        for mut i in arr("images") {
            shift(&mut i, "bufferView", view0);
            self.images.push(i);
        }
        for mut t in arr("textures") {
            shift(&mut t, "source", img0);
            shift(&mut t, "sampler", smp0);
            self.textures.push(t);
        }
        self.samplers.extend(arr("samplers"));
        for mut m in arr("materials") {
            for slot in ["normalTexture", "occlusionTexture", "emissiveTexture"] {
                if let Some(t) = m.get_mut(slot) {
                    shift(t, "index", tex0);
                }
            }
            if let Some(pbr) = m.get_mut("pbrMetallicRoughness") {
                for slot in ["baseColorTexture", "metallicRoughnessTexture"] {
                    if let Some(t) = pbr.get_mut(slot) {
                        shift(t, "index", tex0);
                    }
                }
            }
            self.materials.push(m);
        }
        for mut mesh in arr("meshes") {
            if let Some(prims) = mesh.get_mut("primitives").and_then(Value::as_array_mut) {
                for p in prims {
                    shift(p, "indices", acc0);
                    shift(p, "material", mat0);
                    if let Some(attrs) = p.get_mut("attributes").and_then(Value::as_object_mut) {
                        for v in attrs.values_mut() {
                            if let Some(i) = v.as_u64() {
                                *v = json!(i as usize + acc0);
                            }
                        }
                    }
                }
            }
            self.meshes.push(mesh);
        }
        if self.meshes.len() == mesh0 {
            return Err("no mesh".into());
        }
        Ok(mesh0)
    }
}

/// A z-up point as glTF's y up.
fn y_up(v: glam::DVec3) -> [f32; 3] {
    [v.x as f32, v.z as f32, -v.y as f32]
}

/// A glTF y-up point as z up (the inverse of [`y_up`]).
fn z_up([x, y, z]: [f32; 3]) -> glam::DVec3 {
    glam::DVec3::new(x as f64, -z as f64, y as f64)
}

/// The sampler of the paintings: linear, clamped at the edges.
fn painting_sampler() -> Value {
    json!({ "magFilter": 9729, "minFilter": 9987, "wrapS": 33071, "wrapT": 33071 })
}

/// The dwelling's GLB bytes.
pub(super) fn write(d: &Dwelling, catalogue: &Catalogue) -> Result<Vec<u8>, DwellingError> {
    let mut out = Out::default();
    for look in Look::ALL {
        out.materials.push(look.material());
    }
    for b in &d.built {
        let (mut pos, mut nrm, mut idx) = (Vec::new(), Vec::new(), Vec::<u32>::new());
        for (lo, hi) in &b.blocks {
            box_faces(*lo, *hi, &mut pos, &mut nrm, &mut idx);
        }
        let p = out.floats(&pos, true);
        let n = out.floats(&nrm, false);
        let i = out.indices(&idx);
        let mut attributes = json!({ "POSITION": p, "NORMAL": n });
        let material = match &b.painting {
            Some(painting) => {
                let uv: Vec<[f32; 2]> = pos
                    .iter()
                    .map(|&[x, y, z]| painting.uv(z_up([x, y, z])))
                    .collect();
                attributes["TEXCOORD_0"] = json!(out.floats(&uv, false));
                out.painting(&b.name, &painting.png())
            }
            None => Look::ALL
                .iter()
                .position(|&l| l == b.look)
                .expect("a listed look"),
        };
        out.meshes.push(json!({
            "name": b.name,
            "primitives": [{ "attributes": attributes, "indices": i, "material": material }],
        }));
        out.nodes
            .push(json!({ "name": b.name, "mesh": out.meshes.len() - 1 }));
    }
    let mut model_mesh = std::collections::BTreeMap::new();
    for (k, p) in d.placed.iter().enumerate() {
        let mesh = match model_mesh.get(&p.model) {
            Some(&m) => m,
            None => {
                let model = &catalogue.models[&p.model];
                let path = catalogue.model_path(model);
                let bytes = std::fs::read(&path).map_err(|e| DwellingError::Model {
                    path: path.clone(),
                    message: e.to_string(),
                })?;
                let m = out.model(&bytes).map_err(|message| DwellingError::Model {
                    path: path.clone(),
                    message,
                })?;
                model_mesh.insert(p.model.clone(), m);
                m
            }
        };
        let half = p.yaw() / 2.0;
        out.nodes.push(json!({
            "name": super::piece_name(p, k),
            "mesh": mesh,
            "rotation": [0.0, half.sin(), 0.0, half.cos()],
            "translation": [p.centre[0], p.z_m, -p.centre[1]],
        }));
    }
    let mut root = Map::new();
    root.insert("asset".into(), json!({ "version": "2.0", "generator": format!("egogen scene generate (dwelling v{})", super::DWELLING_VERSION) }));
    root.insert(
        "extensionsUsed".into(),
        json!(["KHR_materials_emissive_strength"]),
    );
    root.insert("scene".into(), json!(0));
    root.insert(
        "scenes".into(),
        json!([{ "nodes": (0..out.nodes.len()).collect::<Vec<_>>() }]),
    );
    pad(&mut out.bin, 0);
    root.insert("buffers".into(), json!([{ "byteLength": out.bin.len() }]));
    for (key, list) in [
        ("nodes", out.nodes),
        ("meshes", out.meshes),
        ("accessors", out.accessors),
        ("bufferViews", out.views),
        ("materials", out.materials),
        ("textures", out.textures),
        ("images", out.images),
        ("samplers", out.samplers),
    ] {
        if !list.is_empty() {
            root.insert(key.into(), Value::Array(list));
        }
    }
    let mut json = serde_json::to_vec(&Value::Object(root)).expect("JSON serialises");
    pad(&mut json, b' ');
    let length = 12 + 8 + json.len() + 8 + out.bin.len();
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: length as u32,
        },
        json: std::borrow::Cow::Owned(json),
        bin: Some(std::borrow::Cow::Owned(out.bin)),
    };
    glb.to_vec().map_err(|e| DwellingError::Model {
        path: "dwelling.glb".into(),
        message: e.to_string(),
    })
}

/// A box's six faces (four vertices each, outward normals), y up.
fn box_faces(
    lo: glam::DVec3,
    hi: glam::DVec3,
    pos: &mut Vec<[f32; 3]>,
    nrm: &mut Vec<[f32; 3]>,
    idx: &mut Vec<u32>,
) {
    use glam::DVec3 as V;
    let c = |i: usize| {
        V::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Corners of each face, counter-clockwise seen from outside, with the face's normal.
    let faces: [([usize; 4], V); 6] = [
        ([0, 2, 3, 1], V::NEG_Z),
        ([4, 5, 7, 6], V::Z),
        ([0, 1, 5, 4], V::NEG_Y),
        ([2, 6, 7, 3], V::Y),
        ([0, 4, 6, 2], V::NEG_X),
        ([1, 3, 7, 5], V::X),
    ];
    for (q, n) in faces {
        let base = pos.len() as u32;
        for &i in &q {
            pos.push(y_up(c(i)));
            nrm.push(y_up(n));
        }
        idx.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
}

/// Pads `bytes` with `with` to a multiple of four bytes (glTF's alignment of chunks and views).
fn pad(bytes: &mut Vec<u8>, with: u8) {
    bytes.resize(bytes.len().next_multiple_of(4), with);
}
