//! Bad body model files fail with an error that names the file, the key and what was expected.

mod common;

use common::*;
use egogen::body::{BodyModel, ModelFileError};

fn load_modified(
    edit: impl FnOnce(&mut Vec<(&'static str, Arr)>),
) -> (
    std::path::PathBuf,
    Result<BodyModel, ModelFileError>,
    tempfile::TempDir,
) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("SMPLX_NEUTRAL.npz");
    let mut arrays = tiny_model_arrays();
    edit(&mut arrays);
    write_npz(&path, &arrays);
    let r = BodyModel::load(&path);
    (path, r, dir)
}

fn expect_error(
    edit: impl FnOnce(&mut Vec<(&'static str, Arr)>),
    needles: &[&str],
) -> ModelFileError {
    let (path, r, _dir) = load_modified(edit);
    let err = r.expect_err("a bad model must not load");
    let msg = err.to_string();
    assert!(
        msg.contains(&path.display().to_string()),
        "names the file: {msg}"
    );
    for n in needles {
        assert!(msg.contains(n), "`{n}` missing from: {msg}");
    }
    err
}

#[test]
fn tiny_model_loads() {
    let (_, r, _dir) = load_modified(|_| {});
    let m = r.unwrap();
    assert_eq!(
        (m.num_vertices(), m.num_betas(), m.num_expression()),
        (20, 10, 10)
    );
    assert!(!m.has_pose_correctives());
}

#[test]
fn missing_key() {
    let e = expect_error(
        |a| a.retain(|(k, _)| *k != "J_regressor"),
        &["missing key `J_regressor`", "[55, 20]"],
    );
    assert!(matches!(e, ModelFileError::MissingKey { .. }));
}

#[test]
fn wrong_shape() {
    let e = expect_error(
        |a| {
            let i = a.iter().position(|(k, _)| *k == "weights").unwrap();
            a[i].1 = Arr::F64(vec![20, 24], vec![0.0; 20 * 24]);
        },
        &["`weights`", "[20, 24]", "expected [20, 55]"],
    );
    assert!(matches!(e, ModelFileError::Shape { .. }));
}

#[test]
fn nan_value() {
    let e = expect_error(
        |a| {
            let i = a.iter().position(|(k, _)| *k == "shapedirs").unwrap();
            let mut d = vec![0.0; 20 * 3 * 20];
            d[77] = f64::NAN;
            a[i].1 = Arr::F64(vec![20, 3, 20], d);
        },
        &["`shapedirs`", "non-finite", "index 77"],
    );
    assert!(matches!(e, ModelFileError::NonFinite { index: 77, .. }));
}

#[test]
fn face_index_out_of_range() {
    expect_error(
        |a| {
            let i = a.iter().position(|(k, _)| *k == "f").unwrap();
            a[i].1 = Arr::U32(vec![1, 3], vec![0, 1, 99]);
        },
        &["`f`", "99", "outside 0..20"],
    );
}

#[test]
fn wrong_parent_table() {
    expect_error(
        |a| {
            let i = a.iter().position(|(k, _)| *k == "kintree_table").unwrap();
            let mut k: Vec<i64> = PARENTS.iter().copied().chain(0..55).collect();
            k[16] = 12;
            a[i].1 = Arr::I64(vec![2, 55], k);
        },
        &[
            "`kintree_table`",
            "joint 16 has parent 12",
            "SMPL-X parent 13",
        ],
    );
}

#[test]
fn vertex_without_weight() {
    expect_error(
        |a| {
            let i = a.iter().position(|(k, _)| *k == "weights").unwrap();
            let mut w = vec![0.0; 20 * 55];
            for v in 1..20 {
                w[v * 55] = 1.0;
            }
            a[i].1 = Arr::F64(vec![20, 55], w);
        },
        &["`weights`", "vertex 0 has no skin weight"],
    );
}

#[test]
fn not_a_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.npz");
    std::fs::write(&path, b"this is not a zip archive").unwrap();
    let msg = BodyModel::load(&path).unwrap_err().to_string();
    assert!(
        msg.contains("model.npz") && msg.contains("cannot open"),
        "{msg}"
    );
    let missing = dir.path().join("nope.npz");
    let msg = BodyModel::load(&missing).unwrap_err().to_string();
    assert!(msg.contains("nope.npz"), "{msg}");
}

/// The tiny model's triangle count (the rows `ft` must have).
fn num_faces(a: &[(&'static str, Arr)]) -> u64 {
    match &a.iter().find(|(k, _)| *k == "f").unwrap().1 {
        Arr::U32(shape, _) => shape[0],
        _ => panic!("`f` is u32"),
    }
}

#[test]
fn uvs_load_corner_for_corner_and_need_both_keys_and_valid_indices() {
    let uv_arrays = |a: &mut Vec<(&'static str, Arr)>, bad_index: Option<u32>| {
        let nf = num_faces(a);
        let mut ft: Vec<u32> = (0..3 * nf as u32).map(|i| i % 4).collect();
        if let Some(bad) = bad_index {
            ft[5] = bad;
        }
        a.push((
            "vt",
            Arr::F64(vec![4, 2], vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]),
        ));
        a.push(("ft", Arr::U32(vec![nf, 3], ft)));
    };
    let (_, r, _dir) = load_modified(|a| uv_arrays(a, None));
    let m = r.unwrap();
    let uvs = m.uvs.as_ref().expect("vt/ft read");
    assert_eq!(uvs.faces.len(), m.faces.len());
    assert_eq!(
        uvs.per_corner()[..5],
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0]]
    );
    let (_, r, _dir) = load_modified(|_| {});
    assert!(r.unwrap().uvs.is_none(), "UVs are optional");

    expect_error(
        |a| {
            uv_arrays(a, None);
            a.retain(|(k, _)| *k != "ft");
        },
        &["`ft`", "is missing while `vt` is there"],
    );
    expect_error(
        |a| {
            uv_arrays(a, None);
            a.retain(|(k, _)| *k != "vt");
        },
        &["`vt`", "is missing while `ft` is there"],
    );
    expect_error(
        |a| uv_arrays(a, Some(4)),
        &["`ft`", "UV index 4 at flat index 5", "0..4"],
    );
    let e = expect_error(
        |a| {
            uv_arrays(a, None);
            let nf = num_faces(a);
            a.retain(|(k, _)| *k != "ft");
            a.push((
                "ft",
                Arr::U32(vec![nf + 1, 3], vec![0; 3 * (nf as usize + 1)]),
            ));
        },
        &["`ft`", "expected ["],
    );
    assert!(matches!(e, ModelFileError::Shape { .. }));
}
