//! Scene files: OBJ, PLY and glTF load with names, metres and z up; bad scenes fail with the
//! file named and a reason.

mod common;

use std::path::Path;

use egogen::scene::{load_scene, walkable_map, SceneError, SceneFrame, UpAxis, WalkableSettings};

const ROOM_OBJ: &str = "\
o floor
v -2 -2 0
v 2 -2 0
v 2 2 0
v -2 2 0
f 1 2 3 4
o table
v -0.5 -0.5 0.7
v 0.5 -0.5 0.7
v 0.5 0.5 0.7
v -0.5 0.5 0.7
v -0.5 -0.5 0.0
v 0.5 -0.5 0.0
f 5 6 7 8
f 9 10 6 5
";

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn obj_keeps_objects_and_builds_a_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "room.obj", ROOM_OBJ);
    let mesh = load_scene(&path, Default::default()).unwrap();
    let names: Vec<&str> = mesh.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["floor", "table"]);
    assert_eq!(mesh.triangles.len(), 6);
    let map = walkable_map(&mesh, &path, WalkableSettings::default()).unwrap();
    assert_eq!(map.floor_z_m, 0.0);
    // The table top (0.7 m) blocks its 1 m × 1 m footprint; the floor around it is walkable.
    assert!(!map.is_walkable_at(glam::DVec2::new(0.0, 0.0)));
    assert!(map.is_walkable_at(glam::DVec2::new(1.5, 1.5)));
    assert!(
        !map.is_walkable_at(glam::DVec2::new(2.5, 0.0)),
        "no floor outside the room"
    );
}

/// What `[render.materials]` reads of an object's own look: an MTL's `map_Kd` makes it
/// textured, `d` below 1 see-through; shipped scenes: the apartment has no texture, the small
/// house mostly textures.
#[test]
fn objects_say_whether_they_are_textured_or_see_through() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "room.mtl",
        "newmtl boards\nKd 0.5 0.4 0.3\nmap_Kd boards.png\nnewmtl glass\nKd 1 1 1\nd 0.3\n",
    );
    let obj = ROOM_OBJ
        .replace("o floor\n", "mtllib room.mtl\no floor\nusemtl boards\n")
        .replace("o table\n", "o table\nusemtl glass\n");
    let path = write(dir.path(), "room.obj", &obj);
    let mesh = load_scene(&path, Default::default()).unwrap();
    let look: Vec<(&str, bool, bool)> = mesh
        .objects
        .iter()
        .map(|o| (o.name.as_str(), o.textured, o.see_through))
        .collect();
    assert_eq!(look, [("floor", true, false), ("table", false, true)]);
    let plain = load_scene(
        &write(dir.path(), "plain.obj", ROOM_OBJ),
        Default::default(),
    )
    .unwrap();
    assert!(plain.objects.iter().all(|o| !o.textured && !o.see_through));
    let shipped = |name: &str| {
        let mesh = load_scene(
            &common::repo_root().join("assets/scenes").join(name),
            Default::default(),
        )
        .unwrap();
        let textured = mesh.objects.iter().filter(|o| o.textured).count();
        (textured, mesh.objects.len())
    };
    assert_eq!(shipped("apartment.glb").0, 0);
    let (textured, all) = shipped("small_house.glb");
    assert!(textured > all / 2 && textured < all, "{textured} of {all}");
}

#[test]
fn ply_and_y_up() {
    let dir = tempfile::tempdir().unwrap();
    // A y-up floor quad at height 0 plus a 1 m tall pole (y is up in this file).
    let ply = "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n\
element face 2\nproperty list uchar int vertex_indices\nend_header\n\
-2 0 -2\n2 0 -2\n2 0 2\n-2 0 2\n0 0 0\n0.2 1.5 0\n0 1.5 0.2\n4 3 2 1 0\n3 4 5 6\n";
    let path = write(dir.path(), "scan.ply", ply);
    let mesh = load_scene(&path, SceneFrame::new(Some(UpAxis::Y), None).unwrap()).unwrap();
    let (lo, hi) = mesh.bounds().unwrap();
    assert!(
        (hi.z - 1.5).abs() < 1e-6 && lo.z.abs() < 1e-6,
        "y-up became z-up: {lo:?} {hi:?}"
    );
    assert!((lo.y + 2.0).abs() < 1e-6 && (hi.y - 2.0).abs() < 1e-6);
    assert!(walkable_map(&mesh, &path, WalkableSettings::default()).is_ok());
    // Read as z-up the floor stands vertical: no floor.
    let as_z = load_scene(&path, SceneFrame::new(Some(UpAxis::Z), None).unwrap()).unwrap();
    let err = walkable_map(&as_z, &path, WalkableSettings::default()).unwrap_err();
    assert!(matches!(err, SceneError::NoFloor { .. }), "{err}");
    assert!(err.to_string().contains("scan.ply") && err.to_string().contains("up_axis"));
}

#[test]
fn gltf_with_embedded_buffer_is_y_up() {
    // One triangle at y = 0 (the floor in glTF's y-up frame) in node "floor".
    let floats: [f32; 9] = [-1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0, -1.0];
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    let b64 = base64_encode(&bytes);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"name":"floor","mesh":0,"translation":[0,0.5,0]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
    );
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "tri.gltf", &json);
    let mesh = load_scene(&path, Default::default()).unwrap();
    assert_eq!(mesh.objects[0].name, "floor");
    // Node translation y = 0.5 (up) → world z = 0.5; glTF z = 1 → world y = −1.
    assert!(mesh.vertices.iter().all(|v| (v.z - 0.5).abs() < 1e-6));
    assert!((mesh.vertices[0].y + 1.0).abs() < 1e-6);
}

fn base64_encode(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[test]
fn shipped_apartment_loads_like_a_floor_plan() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/apartment.glb");
    let mesh = load_scene(&path, Default::default()).unwrap();
    assert!(mesh.objects.iter().any(|o| o.name == "floor"));
    assert!(mesh.objects.iter().any(|o| o.name == "IKEA_sofa_EKTORP"));
    let (lo, hi) = mesh.bounds().unwrap();
    assert!(
        (hi.z - 2.5).abs() < 0.05 && lo.z > -0.05,
        "walls 2.5 m high, floor at 0: {lo:?} {hi:?}"
    );
    let map = walkable_map(&mesh, &path, WalkableSettings::default()).unwrap();
    let area = map.walkable_count() as f64 * 0.01;
    assert!((40.0..120.0).contains(&area), "walkable area {area} m²");
}

/// A shipped scene: its object count, some of its names, the height of its top (floor at 0)
/// and the range of its walkable area (m²).
fn check_shipped_scene(file: &str, objects: usize, names: &[&str], top_z: f64, area: (f64, f64)) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(file);
    let mesh = load_scene(&path, Default::default()).unwrap();
    assert_eq!(mesh.objects.len(), objects, "{file}");
    for name in names {
        assert!(
            mesh.objects.iter().any(|o| o.name == *name),
            "{file}: {name}"
        );
    }
    let (lo, hi) = mesh.bounds().unwrap();
    assert!(
        (hi.z - top_z).abs() < 0.05 && lo.z.abs() < 0.01,
        "{file}: top at {top_z} m, floor at 0: {lo:?} {hi:?}"
    );
    let map = walkable_map(&mesh, &path, WalkableSettings::default()).unwrap();
    let walkable = map.walkable_count() as f64 * 0.01;
    assert!(
        (area.0..area.1).contains(&walkable),
        "{file}: walkable area {walkable} m²"
    );
}

#[test]
fn shipped_held_out_houses_load_with_their_rooms_and_furniture_named() {
    let small_house = [
        "FloorB_01_001",
        "HouseWallB_01_001",
        "RoomWall_01_001",
        "Bed_01_001",
        "FoldingDoor_01_001",
        "Ball_01_003",
    ];
    check_shipped_scene("small_house.glb", 87, &small_house, 3.0, (120.0, 170.0));
    let turtlebot3_house = [
        "floor",
        "turtlebot3_house",
        "turtlebot3_house::cafe_table",
        "turtlebot3_house::bookshelf_1",
    ];
    check_shipped_scene(
        "turtlebot3_house.glb",
        15,
        &turtlebot3_house,
        2.5,
        (130.0, 170.0),
    );
}

fn expect_err(name: &str, text: &str, needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), name, text);
    let err = load_scene(&path, Default::default())
        .and_then(|m| walkable_map(&m, &path, WalkableSettings::default()).map(|_| ()))
        .unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains(name) && msg.contains(needle), "{msg}");
}

#[test]
fn bad_scenes_fail_clearly() {
    expect_err("empty.obj", "", "no triangles");
    expect_err(
        "wall.obj",
        "v 0 0 0\nv 1 0 0\nv 1 0 2\nv 0 0 2\nf 1 2 3 4\n",
        "no floor",
    );
    expect_err(
        "nan.obj",
        "v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n",
        "non-finite vertex (index 1)",
    );
    expect_err("scene.fbx", "whatever", "unsupported format `.fbx`");
    expect_err("broken.glb", "not a glb", "cannot read");
    // A floor covered everywhere by a 1 m slab.
    let covered = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\nv -2 -2 1\nv 2 -2 1\nv 2 2 1\nv -2 2 1\nf 5 6 7 8\n";
    expect_err("covered.obj", covered, "no walkable cell");
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.obj");
    assert!(load_scene(&missing, Default::default())
        .unwrap_err()
        .to_string()
        .contains("missing.obj"));
}

#[test]
fn a_map_too_fine_for_memory_is_refused_with_its_size() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "room.obj", ROOM_OBJ);
    let mesh = load_scene(&path, Default::default()).unwrap();
    for cell_m in [1e-5, 0.0, -0.1, f64::NAN] {
        let settings = WalkableSettings {
            cell_m,
            ..WalkableSettings::default()
        };
        let err = walkable_map(&mesh, &path, settings).unwrap_err();
        assert!(
            matches!(err, SceneError::MapTooLarge { .. }),
            "{cell_m}: {err}"
        );
        let msg = err.to_string();
        assert!(
            msg.contains("room.obj") && msg.contains("cell size"),
            "{msg}"
        );
    }
    // 1e-5 m cells over a room metres wide: the error states the memory it would take.
    let err = walkable_map(
        &mesh,
        &path,
        WalkableSettings {
            cell_m: 1e-5,
            ..WalkableSettings::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("GB"), "{err}");
}

#[test]
fn the_hollow_inside_of_a_closed_wall_is_not_floor() {
    use egogen::math::Vec3;
    use egogen::scene::{SceneMesh, WalkableMap};
    // A 6 × 6 m floor plane, a wall 0.6 m thick modelled as a closed box (as BIM exports are),
    // a free-standing closed pillar, and an open ceiling plane over everything.
    let mut mesh = SceneMesh::default();
    let plane = |z: f64| {
        [
            Vec3::new(-3.0, -3.0, z),
            Vec3::new(3.0, -3.0, z),
            Vec3::new(3.0, 3.0, z),
            Vec3::new(-3.0, 3.0, z),
        ]
    };
    mesh.add_object("floor", &plane(0.0), &[[0, 1, 2], [0, 2, 3]]);
    mesh.add_object("ceiling", &plane(2.5), &[[0, 2, 1], [0, 3, 2]]);
    mesh.add_box(
        "wall",
        Vec3::new(0.53, -3.0, 0.0),
        Vec3::new(1.13, 3.0, 2.5),
    );
    mesh.add_box(
        "pillar",
        Vec3::new(-2.07, -2.07, 0.0),
        Vec3::new(-1.43, -1.43, 2.5),
    );
    let map = WalkableMap::build(&mesh, WalkableSettings::default()).unwrap();
    let walkable = |x: f64, y: f64| map.is_walkable_at(glam::DVec2::new(x, y));
    for y in [-2.0, 0.0, 2.5] {
        assert!(!walkable(0.83, y), "inside the wall at y = {y}");
    }
    assert!(!walkable(-1.75, -1.75), "inside the pillar");
    assert!(
        walkable(-1.0, 0.0) && walkable(2.0, 0.0),
        "the floor on both sides"
    );
    // Two regions (either side of the wall), none inside it.
    let regions: std::collections::BTreeSet<u32> =
        map.component.iter().copied().filter(|&c| c > 0).collect();
    assert_eq!(regions.len(), 2, "{regions:?}");
}

/// Each object's name and label.
fn names_and_labels(mesh: &egogen::scene::SceneMesh) -> Vec<(&str, Option<&str>)> {
    mesh.objects
        .iter()
        .map(|o| (o.name.as_str(), o.label.as_deref()))
        .collect()
}

/// A ScanNet scan (`*_vh_clean_2.labels.ply`: vertex colours and the vertex's NYU40 class as
/// `label`) splits into one object per class, each labelled with the class's name; a vertex
/// `object_id` beside `label` wins (the ids are objects, the classes then unknown).
#[test]
fn a_scannet_ply_splits_by_its_nyu40_labels() {
    let dir = tempfile::tempdir().unwrap();
    let header = |id: &str| {
        format!("ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n\
property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n{id}property ushort label\n\
element face 3\nproperty list uchar int vertex_indices\nend_header\n")
    };
    let body = "-2 -2 0 9 9 9 255 2\n2 -2 0 9 9 9 255 2\n2 2 0 9 9 9 255 2\n-2 2 0 9 9 9 255 2\n\
0 0 0 200 10 10 255 5\n0.2 0 1.5 200 10 10 255 5\n0 0.2 1.5 200 10 10 255 5\n3 0 1 2\n3 0 2 3\n3 4 5 6\n";
    let path = write(
        dir.path(),
        "scene0000_00_vh_clean_2.labels.ply",
        &(header("") + body),
    );
    let mesh = load_scene(&path, Default::default()).unwrap();
    let objects = names_and_labels(&mesh);
    assert_eq!(
        objects,
        [
            ("scene0000_00_vh_clean_2.labels_2", Some("floor")),
            ("scene0000_00_vh_clean_2.labels_5", Some("chair")),
        ]
    );
    assert_eq!(mesh.file_face_objects.as_deref(), Some(&[0, 0, 1][..]));
    assert!(walkable_map(&mesh, &path, WalkableSettings::default()).is_ok());

    // With object ids on the vertices, those split the scan (no class known).
    let with_ids = header("property int object_id\n")
        + "-2 -2 0 9 9 9 255 11 2\n2 -2 0 9 9 9 255 11 2\n2 2 0 9 9 9 255 11 2\n-2 2 0 9 9 9 255 11 2\n\
0 0 0 200 10 10 255 12 5\n0.2 0 1.5 200 10 10 255 12 5\n0 0.2 1.5 200 10 10 255 12 5\n3 0 1 2\n3 0 2 3\n3 4 5 6";
    let path = write(dir.path(), "ids.ply", &(with_ids + "\n"));
    let mesh = load_scene(&path, Default::default()).unwrap();
    let objects = names_and_labels(&mesh);
    assert_eq!(objects, [("ids_11", None), ("ids_12", None)]);
}

/// A scan whose vertices carry `objectId` (as some scanners write it) splits into one object per
/// id, a face taking its first vertex's id; each object holds only the vertices it uses. A
/// Replica `info_semantic.json` beside the file that is not what it should be is refused by name.
#[test]
fn a_ply_with_vertex_object_ids_splits_by_id() {
    let dir = tempfile::tempdir().unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n\
property int objectId\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
-2 -2 0 5\n2 -2 0 5\n2 2 0 5\n-2 2 0 5\n0 0 0 9\n0.2 0 1.5 9\n0 0.2 1.5 9\n4 0 1 2 3\n3 4 5 6\n";
    let path = write(dir.path(), "scan.ply", ply);
    let mesh = load_scene(&path, Default::default()).unwrap();
    let objects = names_and_labels(&mesh);
    assert_eq!(objects, [("scan_5", None), ("scan_9", None)]);
    assert_eq!(mesh.vertices.len(), 7, "each vertex copied once");
    assert_eq!(mesh.triangles.len(), 3);
    assert_eq!(mesh.file_face_objects.as_deref(), Some(&[0, 1][..]));
    assert!(walkable_map(&mesh, &path, WalkableSettings::default()).is_ok());

    write(
        dir.path(),
        "info_semantic.json",
        r#"{"objects": [{"id": "five", "class_name": 3}]}"#,
    );
    let err = load_scene(&path, Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("info_semantic.json") && err.contains("objects[0]"),
        "{err}"
    );
}

/// `egogen scene inspect --depth-images` draws each sample agent's depth image to the right of
/// the map (one per agent, framed in its start's colour); without the flag the picture is the
/// map alone.
#[test]
fn scene_inspect_draws_depth_images_beside_the_map_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
            .args([
                "scene",
                "inspect",
                "scenario:single_box",
                "--agents",
                "2",
                "--out",
            ])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        assert!(
            status.status.success(),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
        common::png_size(&out)
    };
    let (plain_w, plain_h) = run("plain.png", &[]);
    let (w, h) = run("depth.png", &["--depth-images"]);
    // The depth images' column: 32 × 8 px plus a 3 px frame each side and 16 px of margin.
    assert_eq!(w, plain_w + 32 * 8 + 6 + 16);
    assert!(h >= plain_h, "{h} < {plain_h}");
}

/// The shipped stepped house is what `tools/make_stepped_house.py` writes, and its rooms are
/// walked on their own floors with `floor_steps_m`: on one flat floor only the den (the lowest)
/// is walkable; stepped, all four rooms and the middle step form one region, each cell on its
/// room's floor.
#[test]
fn the_stepped_house_is_walked_on_each_rooms_floor() {
    let root = common::repo_root();
    let shipped = root.join("assets/scenes/stepped_house.obj");
    let dir = tempfile::tempdir().unwrap();
    let again = dir.path().join("stepped_house.obj");
    let status = std::process::Command::new("python3")
        .arg(root.join("tools/make_stepped_house.py"))
        .arg(&again)
        .status()
        .expect("python3 runs");
    assert!(status.success());
    assert_eq!(
        std::fs::read(&shipped).unwrap(),
        std::fs::read(&again).unwrap(),
        "assets/scenes/stepped_house.obj differs from the tool's output"
    );
    let mesh = load_scene(&shipped, Default::default()).unwrap();
    let area = |m: &egogen::scene::WalkableMap| m.walkable_count() as f64 * m.cell_m * m.cell_m;
    let flat = walkable_map(&mesh, &shipped, WalkableSettings::default()).unwrap();
    assert!((flat.floor_z_m + 0.12).abs() < 1e-6, "{}", flat.floor_z_m);
    assert!(area(&flat) < 20.0, "{} m² on one flat floor", area(&flat));
    let map = walkable_map(
        &mesh,
        &shipped,
        WalkableSettings {
            floor_steps_m: Some(0.2),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(area(&map) > 75.0, "{} m² on stepped floors", area(&map));
    let regions: std::collections::BTreeSet<u32> =
        map.component.iter().copied().filter(|&c| c > 0).collect();
    assert_eq!(regions.len(), 1);
    for (x, y, floor) in [
        (4.0, 4.0, 0.0),
        (8.0, 6.0, 0.17),
        (8.0, 2.0, -0.12),
        (9.5, 3.7, 0.02),
    ] {
        let p = glam::DVec2::new(x, y);
        let (i, j) = map.cell_of(p).unwrap();
        assert!(map.is_walkable_at(p), "({x}, {y})");
        assert!(
            (map.cell_floor_m(j * map.nx + i) - floor).abs() < 1e-6,
            "({x}, {y}): floor {} m, not {floor} m",
            map.cell_floor_m(j * map.nx + i)
        );
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

    /// Stepped floors far from the origin (x, y to ±100 km, as georeferenced scans lie; the
    /// floor to ±1 km): a platform `rise` m over a floor is walked on its own floor when the
    /// steps allow it and blocked when they do not, and the floor a body follows is finite,
    /// between the two floors and never falls across the step.
    #[test]
    fn stepped_floors_hold_far_from_the_origin(
        ox in -1e5f64..1e5,
        oy in -1e5f64..1e5,
        oz in -1e3f64..1e3,
        // Up to 1 mm under the step limit (0.2 m): floor heights are kept in f32, whose
        // spacing at 1 km is 6e-5 m, so a rise closer to the limit than that is either.
        rise in 0.02f64..0.199,
    ) {
        use egogen::math::Vec3;
        let mut mesh = egogen::scene::SceneMesh::default();
        let at = |x: f64, y: f64, z: f64| Vec3::new(ox + x, oy + y, oz + z);
        mesh.add_box("slab", at(-5.0, -3.0, -0.1), at(5.0, 3.0, 0.0));
        mesh.add_box("platform", at(1.0, -3.0, 0.0), at(5.0, 3.0, rise));
        let map = |steps: f64| {
            egogen::scene::WalkableMap::build(
                &mesh,
                WalkableSettings { floor_steps_m: Some(steps), ..Default::default() },
            )
            .unwrap()
        };
        let p = |x: f64| glam::DVec2::new(ox + x, oy);
        let stepped = map(0.2);
        let floor = |x: f64| stepped.cell_floor_at(p(x)).unwrap();
        proptest::prop_assert!((floor(-3.0) - oz).abs() < 1e-4, "{} {oz}", floor(-3.0));
        proptest::prop_assert!((floor(3.0) - oz - rise).abs() < 1e-4, "{} {}", floor(3.0), oz + rise);
        proptest::prop_assert!(stepped.is_walkable_at(p(-3.0)) && stepped.is_walkable_at(p(3.0)));
        let region = |m: &egogen::scene::WalkableMap, x: f64| {
            let (i, j) = m.cell_of(p(x)).unwrap();
            m.component[j * m.nx + i]
        };
        proptest::prop_assert_eq!(region(&stepped, -3.0), region(&stepped, 3.0));
        let mut last = f64::NEG_INFINITY;
        for k in 0..=40 {
            let z = stepped.floor_under(p(-1.0 + 0.05 * k as f64));
            proptest::prop_assert!(z.is_finite() && z >= oz - 1e-4 && z <= oz + rise + 1e-4);
            proptest::prop_assert!(z >= last - 1e-4, "the floor falls across the step: {last} then {z}");
            last = z;
        }
        // Steps lower than the platform: it is furniture if higher than the 0.1 m any walker
        // steps over (lower, a sill or a rug: walked over on the floor below).
        let low = map(0.5 * rise);
        proptest::prop_assert!(low.is_walkable_at(p(-3.0)));
        proptest::prop_assert_eq!(low.is_walkable_at(p(3.0)), rise <= 0.1);
    }
}

/// `ROOM_OBJ` (z up, metres) written as another tool would: y up, in `unit_m` metres per unit
/// (a z-up point (x, y, z) is the y-up point (x, z, −y)).
fn room_obj_y_up(unit_m: f64) -> String {
    ROOM_OBJ
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let v: Vec<f64> = rest.split(' ').map(|c| c.parse().unwrap()).collect();
                format!("v {} {} {}\n", v[0] / unit_m, v[2] / unit_m, -v[1] / unit_m)
            }
            None => format!("{l}\n"),
        })
        .collect()
}

#[test]
fn a_file_in_centimetres_or_y_up_is_read_in_metres_z_up_when_told() {
    let dir = tempfile::tempdir().unwrap();
    let metres = load_scene(&write(dir.path(), "m.obj", ROOM_OBJ), Default::default()).unwrap();
    let reference = walkable_map(&metres, Path::new("m.obj"), Default::default()).unwrap();
    for (name, unit_m) in [
        ("y_up_m.obj", 1.0),
        ("y_up_cm.obj", 0.01),
        ("y_up_mm.obj", 0.001),
    ] {
        let path = write(dir.path(), name, &room_obj_y_up(unit_m));
        let frame = SceneFrame::new(Some(UpAxis::Y), Some(unit_m)).unwrap();
        let mesh = load_scene(&path, frame).unwrap();
        assert_eq!(mesh.objects.len(), metres.objects.len());
        let worst = mesh
            .vertices
            .iter()
            .zip(&metres.vertices)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-6,
            "{name}: a vertex {worst} m off (f32 in the file)"
        );
        let map = walkable_map(&mesh, &path, Default::default()).unwrap();
        assert_eq!(map.walkable, reference.walkable, "{name}: another map");
    }
    // Read in its own units, a room in millimetres is 4 000 m across: the map's refusal says
    // what to give.
    let path = dir.path().join("y_up_mm.obj");
    let mesh = load_scene(&path, SceneFrame::new(Some(UpAxis::Y), None).unwrap()).unwrap();
    let err = walkable_map(&mesh, &path, Default::default()).unwrap_err();
    assert!(matches!(err, SceneError::MapTooLarge { .. }), "{err}");
    assert!(err.to_string().contains("unit_m"), "{err}");
    // A y-up floor alone, read z up, stands on edge: the refusal names the key that turns it
    // (the room's table, on its side, would be taken for a floor).
    let floor_only: String = room_obj_y_up(0.001)
        .lines()
        .take(6)
        .map(|l| format!("{l}\n"))
        .collect();
    let path = write(dir.path(), "floor_y_up_mm.obj", &floor_only);
    let mesh = load_scene(&path, SceneFrame::new(None, Some(0.001)).unwrap()).unwrap();
    let err = walkable_map(&mesh, &path, Default::default()).unwrap_err();
    assert!(err.to_string().contains("up_axis"), "{err}");
    // Units that are no length.
    for bad in [0.0, -0.01, f64::NAN, f64::INFINITY, 1e4] {
        let msg = SceneFrame::new(None, Some(bad)).unwrap_err();
        assert!(msg.contains("0.01 for centimetres"), "{bad}: {msg}");
    }
}

/// `egogen scene inspect SCENE ARGS --out PNG`, run.
fn scene_inspect(scene: &Path, args: &[&str], png: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["scene", "inspect"])
        .arg(scene)
        .args(args)
        .arg("--out")
        .arg(png)
        .output()
        .unwrap()
}

/// What a successful `scene inspect` said on stderr.
fn inspect_ok(scene: &Path, args: &[&str], png: &Path) -> String {
    let out = scene_inspect(scene, args, png);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    err
}

/// `egogen scene inspect` warns when the floor it found lies high above the scene's lowest
/// point or the scene is much taller than wide — a room on its side, read with the wrong up
/// axis, walked on a wall's end — and not when the file is read the right way up.
#[test]
fn scene_inspect_warns_of_a_scene_on_its_side() {
    let dir = tempfile::tempdir().unwrap();
    let obj = common::room_y_up_cm_obj();
    let scene = write(dir.path(), "room_cm.obj", &obj);
    let png = |name: &str| dir.path().join(name);
    let sideways = inspect_ok(&scene, &["--unit-m", "0.01"], &png("sideways.png"));
    assert!(
        sideways.contains("warning") && sideways.contains("--up"),
        "{sideways}"
    );
    let upright = inspect_ok(
        &scene,
        &["--unit-m", "0.01", "--up", "y"],
        &png("upright.png"),
    );
    assert!(!upright.contains("warning"), "{upright}");

    // The shipped apartment (glTF, y up) read z up: its floor found lies only 0.57 m above its
    // lowest point, but it stands 10.2 m tall and 2.5 m across; read as it is, no warning.
    let apartment = common::repo_root().join("assets/scenes/apartment.glb");
    let sideways = inspect_ok(&apartment, &["--up", "z"], &png("apartment_z.png"));
    assert!(
        sideways.contains("warning") && sideways.contains("m tall and 2.50 m across"),
        "{sideways}"
    );
    let upright = inspect_ok(&apartment, &[], &png("apartment.png"));
    assert!(!upright.contains("warning"), "{upright}");
}

/// `egogen scene inspect` lists the places to sit it finds: in the shipped apartment the sofa,
/// the bed and chairs, never a table, and draws them on the map.
#[test]
fn scene_inspect_lists_the_apartments_seats() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("apartment.png");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_egogen"))
        .args(["scene", "inspect"])
        .arg(common::repo_root().join("assets/scenes/apartment.glb"))
        .arg("--out")
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let seats: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("seats:"))
        .skip(1)
        .take_while(|l| l.starts_with("            "))
        .collect();
    for object in [
        "IKEA_sofa_EKTORP",
        "IKEA_bed_FJELLSE",
        "IKEA_chair_PELLO",
        "IKEA_chair_STEFAN",
    ] {
        assert!(seats.iter().any(|l| l.contains(object)), "{object}: {text}");
    }
    assert!(
        !seats.iter().any(|l| l.to_lowercase().contains("table")),
        "{text}"
    );
    assert!(png.is_file());
}

/// A scene read at the wrong size or walked at a floor it does not have is refused or warned of
/// naming the key to check: the apartment (in metres) read in millimetres is refused naming
/// `unit_m`, in centimetres (1 walkable cell) warned of naming `unit_m`; a floor asked for
/// far above it, or at a height inside it where there is no floor, is refused naming
/// `floor_z_m`.
#[test]
fn a_scene_at_the_wrong_size_or_floor_names_the_key_to_check() {
    let dir = tempfile::tempdir().unwrap();
    let apartment = common::repo_root().join("assets/scenes/apartment.glb");
    let inspect = |args: &[&str], png: &str| scene_inspect(&apartment, args, &dir.path().join(png));
    let mm = inspect(&["--unit-m", "0.001"], "mm.png");
    let err = String::from_utf8_lossy(&mm.stderr);
    assert!(
        !mm.status.success()
            && err.contains("only 0.01 × 0.01 m across")
            && err.contains("`[scene] unit_m`"),
        "{err}"
    );
    let cm = inspect(&["--unit-m", "0.01"], "cm.png");
    let err = String::from_utf8_lossy(&cm.stderr);
    assert!(
        cm.status.success() && err.contains("warning") && err.contains("`[scene] unit_m`"),
        "{err}"
    );
    let high = inspect(&["--floor-z-m", "50"], "high.png");
    let err = String::from_utf8_lossy(&high.stderr);
    assert!(
        !high.status.success()
            && err
                .contains("`[scene] floor_z_m` = 50 (--floor-z-m) is outside the scene's heights"),
        "{err}"
    );
    let inside = inspect(&["--floor-z-m", "1.2"], "inside.png");
    let err = String::from_utf8_lossy(&inside.stderr);
    assert!(
        !inside.status.success()
            && err.contains("no walkable cell")
            && err.contains("`[scene] floor_z_m`"),
        "{err}"
    );
    assert!(!dir.path().join("mm.png").exists() && !dir.path().join("high.png").exists());
}
