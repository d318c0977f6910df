//! Scenes in every format the loader reads are rendered by `egogen-run` with real Blender, not
//! only glTF: a Wavefront OBJ whose MTL gives the floor an image texture and a wall a plain
//! colour, and a PLY scan-like mesh with vertex colours. Each scene's objects keep their own
//! names in the segmentation id table, their pixels carry those ids, and the colours the files
//! hold are the colours rendered (a red/blue checker on the OBJ's floor, a green wall; the PLY's
//! green floor and red wall); a PLY whose faces carry object ids is split by id, with the
//! labels of Replica's `info_semantic.json`; a glTF with an image texture and a mesh of two
//! materials.

mod common;

use std::path::Path;

/// One walker crossing the room towards the wall at x = 3, wearing the Aria RGB camera.
fn config(scene: &Path) -> String {
    format!(
        r#"
[body]
[motion]
source = "agents"
duration_s = 1.0
seed = 2
[[agents]]
name = "wearer"
start = [-1.5, 0.0]
goals = [[1.5, 0.0]]
[output]
dir = "out"
mesh_every_n_frames = 0
[scene]
path = "{}"
ceiling = false
indoors = false
[render]
cameras = ["camera-rgb"]
resolution_scale = 0.125
every_n_frames = 20
samples = 4
passes = ["colour", "segmentation", "position"]
[supervisor]
workers = 1
"#,
        scene.display()
    )
}

/// The 8 × 8 m floor and the wall (x 3.0–3.2, 2.5 m high) as vertices and quads (1-based).
fn room() -> (Vec<[f64; 3]>, Vec<[usize; 4]>, Vec<[usize; 4]>) {
    let mut v = vec![
        [-4.0, -4.0, 0.0],
        [4.0, -4.0, 0.0],
        [4.0, 4.0, 0.0],
        [-4.0, 4.0, 0.0],
    ];
    for z in [0.0, 2.5] {
        for (x, y) in [(3.0, -4.0), (3.2, -4.0), (3.2, 4.0), (3.0, 4.0)] {
            v.push([x, y, z]);
        }
    }
    let floor = vec![[1, 2, 3, 4]];
    let wall = vec![
        [5, 8, 7, 6],
        [9, 10, 11, 12],
        [5, 6, 10, 9],
        [6, 7, 11, 10],
        [7, 8, 12, 11],
        [8, 5, 9, 12],
    ];
    (v, floor, wall)
}

/// Every frame's pixels: segmentation id, colour (R, G, B) and world position.
#[derive(Clone, Copy)]
struct Pixel {
    id: u32,
    rgb: [f32; 3],
    xyz: [f32; 3],
}

/// The dataset's segmentation id table and every rendered pixel of every frame.
fn rendered(dataset: &Path) -> (Vec<(String, u32)>, Vec<Pixel>) {
    let cam = dataset.join("cameras/camera-rgb");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cam.join("annotations.json")).unwrap())
            .unwrap();
    let ids = doc["segmentation_ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| {
            (
                i["name"].as_str().unwrap().to_owned(),
                i["id"].as_u64().unwrap() as u32,
            )
        })
        .collect();
    let mut pixels = Vec::new();
    for f in doc["frames"].as_array().unwrap() {
        let exr =
            egogen::exr_file::ExrContents::read(&cam.join(f["file"].as_str().unwrap())).unwrap();
        let ch = |name: &str| exr.channel(name).unwrap().values.clone();
        let seg = ch("segmentation.id");
        let rgb = ["rgb.R", "rgb.G", "rgb.B"].map(ch);
        let pos = ["position.X", "position.Y", "position.Z"].map(ch);
        for k in 0..seg.len() {
            pixels.push(Pixel {
                id: seg[k] as u32,
                rgb: [rgb[0][k], rgb[1][k], rgb[2][k]],
                xyz: [pos[0][k], pos[1][k], pos[2][k]],
            });
        }
    }
    (ids, pixels)
}

fn id_of(ids: &[(String, u32)], name: &str) -> u32 {
    ids.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("{name} not in the id table {ids:?}"))
        .1
}

/// The pixels of the floor's and the wall's ids, each many, each lying on its own geometry
/// (position pass: the floor at z = 0, the wall at x 3.0–3.2).
fn floor_and_wall(pixels: &[Pixel], floor_id: u32, wall_id: u32) -> (Vec<&Pixel>, Vec<&Pixel>) {
    let floor: Vec<&Pixel> = pixels.iter().filter(|p| p.id == floor_id).collect();
    let wall: Vec<&Pixel> = pixels.iter().filter(|p| p.id == wall_id).collect();
    assert!(
        floor.len() > 50 && wall.len() > 50,
        "{} floor, {} wall pixels",
        floor.len(),
        wall.len()
    );
    assert!(
        floor.iter().all(|p| p.xyz[2].abs() < 0.01),
        "a floor pixel off the floor"
    );
    assert!(
        wall.iter().all(|p| (2.99..=3.21).contains(&p.xyz[0])),
        "a wall pixel off the wall"
    );
    (floor, wall)
}

/// Share of `pixels` whose colour channel `c` exceeds both others by half again.
fn dominated_by(pixels: &[&Pixel], c: usize) -> f64 {
    let n = pixels
        .iter()
        .filter(|p| (0..3).all(|o| o == c || p.rgb[c] > 1.5 * p.rgb[o]))
        .count();
    n as f64 / pixels.len().max(1) as f64
}

/// The OBJ's wall: a name longer than the 63 bytes Blender keeps, which must still get its id.
const LONG_WALL: &str =
    "wall_between_the_living_room_and_the_kitchen_of_the_flat_on_the_first_floor";

/// `checker.png` in `dir`: a 4 × 4 texel checker, red and blue (the floors' texture, repeated
/// four times across them).
fn write_checker_png(dir: &Path) {
    let mut img = egogen::preview::RgbImage::new(4, 4, [0, 0, 0]);
    for y in 0..4 {
        for x in 0..4 {
            img.pixels[y * 4 + x] = if (x + y) % 2 == 0 {
                [230, 20, 20]
            } else {
                [20, 20, 230]
            };
        }
    }
    img.write_png(&dir.join("checker.png")).unwrap();
}

/// Renders `scene` (a room of a `floor` object that carries the checker and a `wall` one),
/// checks the dataset, the objects' pixels and the floor's two colours; the floor's and the
/// wall's pixels.
fn render_checkered_room(dir: &Path, scene: &Path, wall: &str) -> (Vec<Pixel>, Vec<Pixel>) {
    render_checkered_room_read_as(dir, scene, wall, "")
}

/// [`render_checkered_room`] with `scene_keys` added to the config's `[scene]` (how the file
/// is read: `up_axis`, `unit_m`).
fn render_checkered_room_read_as(
    dir: &Path,
    scene: &Path,
    wall: &str,
    scene_keys: &str,
) -> (Vec<Pixel>, Vec<Pixel>) {
    let config = dir.join("run.toml");
    std::fs::write(
        &config,
        self::config(scene).replace(
            "ceiling = false\n",
            &format!("ceiling = false\n{scene_keys}\n"),
        ),
    )
    .unwrap();
    common::egogen_run_ok(&config);
    let out = dir.join("out");
    assert!(egogen::supervisor::verify(&out).is_ok());
    let (ids, pixels) = rendered(&out);
    let (floor_id, wall_id) = (id_of(&ids, "floor"), id_of(&ids, wall));
    let (floor, wall) = floor_and_wall(&pixels, floor_id, wall_id);
    let (red, blue) = (dominated_by(&floor, 0), dominated_by(&floor, 2));
    assert!(
        red > 0.2 && blue > 0.2,
        "floor red {red:.2}, blue {blue:.2}"
    );
    (
        floor.into_iter().copied().collect(),
        wall.into_iter().copied().collect(),
    )
}

/// `room()` as an OBJ whose MTL gives the floor the checker and the wall (named `LONG_WALL`)
/// green, each vertex written by `written` (the file's frame), beside `checker.png`.
fn write_checkered_obj(dir: &Path, written: impl Fn([f64; 3]) -> [f64; 3]) -> std::path::PathBuf {
    write_checker_png(dir);
    std::fs::write(
        dir.join("room.mtl"),
        "newmtl checker\nKd 1 1 1\nmap_Kd checker.png\nnewmtl green\nKd 0.05 0.8 0.05\n",
    )
    .unwrap();
    let (v, floor, wall) = room();
    let mut obj = String::from("mtllib room.mtl\n");
    for p in v.into_iter().map(written) {
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    obj += "vt 0 0\nvt 4 0\nvt 4 4\nvt 0 4\n";
    obj += "o floor\nusemtl checker\n";
    for q in &floor {
        obj += &format!("f {}/1 {}/2 {}/3 {}/4\n", q[0], q[1], q[2], q[3]);
    }
    obj += &format!("o {LONG_WALL}\nusemtl green\n");
    for q in &wall {
        obj += &format!("f {} {} {} {}\n", q[0], q[1], q[2], q[3]);
    }
    let scene = dir.join("room.obj");
    std::fs::write(&scene, obj).unwrap();
    scene
}

#[test]
fn an_obj_scene_renders_with_its_textures_materials_and_object_names() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_checkered_obj(dir.path(), |p| p);
    let pixels = render_checkered_room(dir.path(), &scene, LONG_WALL);
    let (_, wall) = &pixels;
    // The wall green.
    let green = dominated_by(&wall.iter().collect::<Vec<_>>(), 1);
    assert!(green > 0.8, "wall green {green:.2}");
}

/// An OBJ without `o` or `g` lines is one object named after its file, in the id table and in
/// Blender: its pixels carry that id (not 0, the id of nothing). Faces before the first `o`
/// line are that object too, and the named object after them its own.
#[test]
fn an_obj_without_object_lines_is_one_object_named_after_its_file() {
    let (v, floor, wall) = room();
    let mut vertices = String::new();
    for p in &v {
        vertices += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    let faces = |quads: &[[usize; 4]]| -> String {
        quads
            .iter()
            .map(|q| format!("f {} {} {} {}\n", q[0], q[1], q[2], q[3]))
            .collect()
    };
    for (file, obj, wall_name) in [
        (
            "plain_room.obj",
            format!("{vertices}{}{}", faces(&floor), faces(&wall)),
            "plain_room",
        ),
        (
            "leading.obj",
            format!("{vertices}{}o wall\n{}", faces(&floor), faces(&wall)),
            "wall",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join(file);
        std::fs::write(&scene, obj).unwrap();
        let config = dir.path().join("run.toml");
        std::fs::write(&config, self::config(&scene)).unwrap();
        common::egogen_run_ok(&config);
        let (ids, pixels) = rendered(&dir.path().join("out"));
        let stem = file.trim_end_matches(".obj");
        let floor_id = id_of(&ids, stem);
        assert!(floor_id > 0, "{file}: {ids:?}");
        let wall_id = id_of(&ids, wall_name);
        let on_floor = |p: &&Pixel| p.xyz[2].abs() < 0.01;
        let on_wall = |p: &&Pixel| (2.99..=3.21).contains(&p.xyz[0]);
        let floor = pixels
            .iter()
            .filter(|p| p.id == floor_id && on_floor(p))
            .count();
        let wall = pixels
            .iter()
            .filter(|p| p.id == wall_id && on_wall(p))
            .count();
        assert!(
            floor > 50 && wall > 50,
            "{file}: {floor} floor, {wall} wall pixels with their ids"
        );
        assert!(
            pixels
                .iter()
                .filter(|p| p.id == floor_id || p.id == wall_id)
                .all(|p| on_floor(&p) || on_wall(&p)),
            "{file}: a pixel of the room's ids off the room"
        );
    }
}

/// An OBJ written y up in centimetres (as many modelling tools write one) renders as the same
/// room in metres, z up, when the config says how to read it: the floor's pixels at z = 0 and
/// the wall's at x 3.0–3.2 in the position pass, both textures in place.
#[test]
fn an_obj_in_centimetres_y_up_renders_in_metres_when_told() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_checkered_obj(dir.path(), |[x, y, z]| [100.0 * x, 100.0 * z, -100.0 * y]);
    let (_, wall) = &render_checkered_room_read_as(
        dir.path(),
        &scene,
        LONG_WALL,
        "up_axis = \"y\"\nunit_m = 0.01",
    );
    let green = dominated_by(&wall.iter().collect::<Vec<_>>(), 1);
    assert!(green > 0.8, "wall green {green:.2}");
}

#[test]
fn a_ply_scan_renders_with_its_vertex_colours() {
    let dir = tempfile::tempdir().unwrap();
    let (v, floor, wall) = room();
    // Floor vertices green, wall vertices red (unsigned bytes, as scanners write them).
    let colour = |k: usize| if k < 4 { [30, 200, 30] } else { [200, 30, 30] };
    let faces: Vec<[usize; 4]> = floor.iter().chain(&wall).copied().collect();
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        v.len(),
        faces.len()
    );
    for (k, p) in v.iter().enumerate() {
        let c = colour(k);
        ply += &format!("{} {} {} {} {} {}\n", p[0], p[1], p[2], c[0], c[1], c[2]);
    }
    for q in &faces {
        ply += &format!("4 {} {} {} {}\n", q[0] - 1, q[1] - 1, q[2] - 1, q[3] - 1);
    }
    let scene = dir.path().join("scan.ply");
    std::fs::write(&scene, ply).unwrap();
    let config = dir.path().join("run.toml");
    std::fs::write(&config, self::config(&scene)).unwrap();
    common::egogen_run_ok(&config);

    let (ids, pixels) = rendered(&dir.path().join("out"));
    let scan = id_of(&ids, "scan");
    let floor: Vec<&Pixel> = pixels
        .iter()
        .filter(|p| p.id == scan && p.xyz[2].abs() < 0.01)
        .collect();
    let wall: Vec<&Pixel> = pixels
        .iter()
        .filter(|p| p.id == scan && p.xyz[0] > 2.99)
        .collect();
    assert!(
        floor.len() > 50 && wall.len() > 50,
        "{} floor, {} wall pixels",
        floor.len(),
        wall.len()
    );
    let (green, red) = (dominated_by(&floor, 1), dominated_by(&wall, 0));
    assert!(
        green > 0.8 && red > 0.8,
        "floor green {green:.2}, wall red {red:.2}"
    );
    assert!(egogen::supervisor::verify(&dir.path().join("out")).is_ok());
}

/// A Replica-style scan: a PLY whose faces carry an `object_id` (the floor 3, the wall's faces
/// 7) with Replica's `info_semantic.json` beside it naming their classes. The loader and Blender
/// split it into one object per id (`scan_3`, `scan_7`), the id table carries each object's
/// label, each object's pixels lie on its own geometry, and the vertex colours still show.
#[test]
fn a_ply_scan_with_object_ids_is_split_and_labelled() {
    let dir = tempfile::tempdir().unwrap();
    let (v, floor, wall) = room();
    let colour = |k: usize| if k < 4 { [30, 200, 30] } else { [200, 30, 30] };
    let faces: Vec<([usize; 4], i32)> = floor
        .iter()
        .map(|q| (*q, 3))
        .chain(wall.iter().map(|q| (*q, 7)))
        .collect();
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nelement face {}\n\
         property list uchar int vertex_indices\nproperty int object_id\nend_header\n",
        v.len(),
        faces.len()
    );
    for (k, p) in v.iter().enumerate() {
        let c = colour(k);
        ply += &format!("{} {} {} {} {} {}\n", p[0], p[1], p[2], c[0], c[1], c[2]);
    }
    for (q, id) in &faces {
        ply += &format!(
            "4 {} {} {} {} {id}\n",
            q[0] - 1,
            q[1] - 1,
            q[2] - 1,
            q[3] - 1
        );
    }
    // A stem longer than Blender keeps (63 bytes): the objects' names are cut before their ids.
    let stem = "scan_of_a_room_from_a_scanner_that_writes_long_file_names_like_this_one";
    let scene = dir.path().join(format!("{stem}.ply"));
    std::fs::write(&scene, ply).unwrap();
    std::fs::write(
        dir.path().join("info_semantic.json"),
        r#"{"classes": [], "objects": [{"id": 3, "class_name": "floor"}, {"id": 7, "class_name": "wall"}]}"#,
    )
    .unwrap();
    // The loader's objects, before any render.
    let mesh = egogen::scene::load_scene(&scene, Default::default()).unwrap();
    let loaded: Vec<(&str, Option<&str>)> = mesh
        .objects
        .iter()
        .map(|o| (o.name.as_str(), o.label.as_deref()))
        .collect();
    let (floor_name, wall_name) = (format!("{}_3", &stem[..61]), format!("{}_7", &stem[..61]));
    assert_eq!(
        loaded,
        [
            (floor_name.as_str(), Some("floor")),
            (wall_name.as_str(), Some("wall"))
        ]
    );
    assert_eq!(
        mesh.file_face_objects.as_deref(),
        Some(&[0, 1, 1, 1, 1, 1, 1][..])
    );

    let config = dir.path().join("run.toml");
    std::fs::write(&config, self::config(&scene)).unwrap();
    common::egogen_run_ok(&config);
    let out = dir.path().join("out");
    let (ids, pixels) = rendered(&out);
    let (floor_id, wall_id) = (id_of(&ids, &floor_name), id_of(&ids, &wall_name));
    assert_ne!(floor_id, wall_id);
    let doc: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("cameras/camera-rgb/annotations.json")).unwrap(),
    )
    .unwrap();
    let label = |name: &str| {
        doc["segmentation_ids"]
            .as_array()
            .unwrap()
            .iter()
            .find(|i| i["name"] == name)
            .map(|i| i["label"].clone())
            .unwrap()
    };
    assert_eq!(label(&floor_name), "floor");
    assert_eq!(label(&wall_name), "wall");
    assert!(label("wearer").is_null(), "agents have no label");
    let (floor, wall) = floor_and_wall(&pixels, floor_id, wall_id);
    let (green, red) = (dominated_by(&floor, 1), dominated_by(&wall, 0));
    assert!(
        green > 0.8 && red > 0.8,
        "floor green {green:.2}, wall red {red:.2}"
    );
    // Blender's input is scratch: gone from the finished dataset.
    assert!(!out.join("work/scene_face_objects.npy").exists());
    assert!(egogen::supervisor::verify(&out).is_ok());
}

/// A glTF room whose floor has an image texture (the PNG beside it) and whose wall is one mesh
/// with two materials — green on the face the walker looks at, grey elsewhere: the object names
/// are the nodes', the floor shows the texture and the wall's near face its own material.
/// The room as `tools/make_textured_gltf.py` writes it (the one docs/RENDERING.md shows):
/// `room()`'s floor and wall, glTF y up, the checker PNG beside it, in `dir`.
fn write_textured_gltf(dir: &Path) -> std::path::PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    common::succeeds(
        std::process::Command::new("python3")
            .arg(root.join("tools/make_textured_gltf.py"))
            .arg(dir),
    );
    dir.join("room.gltf")
}

#[test]
fn a_gltf_scene_renders_with_its_textures_and_several_materials() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_textured_gltf(dir.path());
    let (_, wall) = &render_checkered_room(dir.path(), &scene, "wall");
    // The near face green; any other face of the wall in view grey (no channel dominates).
    let near: Vec<&Pixel> = wall.iter().filter(|p| p.xyz[0] < 3.01).collect();
    let other: Vec<&Pixel> = wall.iter().filter(|p| p.xyz[0] > 3.01).collect();
    assert!(near.len() > 50, "{} near-face pixels", near.len());
    let green = dominated_by(&near, 1);
    assert!(green > 0.8, "near face green {green:.2}");
    let coloured = (0..3).map(|c| dominated_by(&other, c)).sum::<f64>();
    assert!(
        coloured < 0.2,
        "other faces coloured {coloured:.2} of {}",
        other.len()
    );
    assert!(egogen::supervisor::verify(&dir.path().join("out")).is_ok());
}

/// A glTF file that breaks its specification — z up, in millimetres, as some exporters write
/// one — renders as the same room when the config says so: each node's matrix turns the
/// y-up metres of `make_textured_gltf.py` into z-up millimetres, which `up_axis = "z"` and
/// `unit_m = 0.001` turn back (Blender's importer turns every glTF as if y up; the run
/// turns it back).
#[test]
fn a_z_up_gltf_in_millimetres_renders_in_metres_when_told() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_textured_gltf(dir.path());
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    // Column-major: (x, y, z) ↦ 1000 (x, −z, y).
    let to_z_up_mm = serde_json::json!([
        1000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1000.0, 0.0, 0.0, -1000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0
    ]);
    for node in doc["nodes"].as_array_mut().unwrap() {
        node["matrix"] = to_z_up_mm.clone();
    }
    std::fs::write(&scene, serde_json::to_string(&doc).unwrap()).unwrap();
    let (_, wall) = &render_checkered_room_read_as(
        dir.path(),
        &scene,
        "wall",
        "up_axis = \"z\"\nunit_m = 0.001",
    );
    let near: Vec<&Pixel> = wall.iter().filter(|p| p.xyz[0] < 3.01).collect();
    let green = dominated_by(&near, 1);
    assert!(green > 0.8, "near face green {green:.2}");
}
