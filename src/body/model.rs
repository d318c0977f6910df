//! The body model in memory: template, blend shapes, regressor, skin weights, topology.

use std::path::{Path, PathBuf};

use super::model_file::{ModelArchive, ModelFileError};
use super::skeleton::{NUM_JOINTS, PARENTS};
use crate::math::{Real, Vec3};

/// Number of pose-corrective features: 54 non-root joints × 9 matrix entries.
pub(crate) const POSE_FEATURES: usize = (NUM_JOINTS - 1) * 9;

/// A sparse row: (index, weight) pairs with non-zero weight.
pub(crate) type SparseRow = Vec<(u32, Real)>;

/// An SMPL-X–layout body model (our CC0 default or the official SMPL-X files).
///
/// Loaded with [`BodyModel::load`]; posed with the functions in `lbs`.
#[derive(Debug, Clone)]
pub struct BodyModel {
    /// File the model came from.
    pub source: PathBuf,
    /// Rest-pose vertices for zero betas (metres, SMPL-X body frame).
    pub v_template: Vec<Vec3>,
    /// Triangles (vertex indices).
    pub faces: Vec<[u32; 3]>,
    /// Shape and expression directions, row-major `(V·3, num_dirs)` as stored in the file.
    pub(crate) dirs: Vec<Real>,
    pub(crate) num_dirs: usize,
    /// Columns of `dirs` used for betas and for expression coefficients (as `smplx` picks them:
    /// 300 + 100 when the file has ≥ 400 columns, else 10 + 10).
    pub(crate) shape_cols: std::ops::Range<usize>,
    pub(crate) expression_cols: std::ops::Range<usize>,
    /// Pose correctives, row-major `(V·3, 486)`, in f32 (as `smplx` computes them: the
    /// product reads half the memory, and a corrective of a few centimetres keeps ~1e-9 m);
    /// `None` when every entry is zero, which skips the V·3 × 486 product entirely.
    pub(crate) posedirs: Option<Vec<f32>>,
    /// Joint regressor, one sparse row of vertex weights per joint.
    pub(crate) j_regressor: Vec<SparseRow>,
    /// Skin weights, one sparse row of joint weights per vertex.
    pub(crate) skin_weights: Vec<SparseRow>,
    /// Texture coordinates, when the file has them (`vt`, `ft`: our model carries
    /// MakeHuman's default UV layout, the official SMPL-X files their own).
    pub uvs: Option<BodyUvs>,
    /// The motion model's marker vertices, chosen on first use ([`BodyModel::marker_ids`]).
    marker_ids: std::sync::OnceLock<Vec<u32>>,
}

/// A body model's UV map: coordinates and, per triangle of [`BodyModel::faces`], the
/// coordinates of its three corners (UV seams give one vertex several coordinates).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyUvs {
    /// `vt`: (u, v) in [0, 1], v up (OBJ's convention, as Blender's).
    pub coords: Vec<[f32; 2]>,
    /// `ft`: per triangle, indices into `coords`, corner for corner with `faces`.
    pub faces: Vec<[u32; 3]>,
}

impl BodyUvs {
    /// Each triangle corner's (u, v), in face order: what a renderer's per-corner UV layer holds.
    pub fn per_corner(&self) -> Vec<[f32; 2]> {
        self.faces
            .iter()
            .flat_map(|t| t.map(|i| self.coords[i as usize]))
            .collect()
    }
}

impl BodyModel {
    /// Loads and validates an SMPL-X `.npz` model file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ModelFileError> {
        let path = path.as_ref();
        let mut ar = ModelArchive::open(path)?;
        let v_template = ar.read("v_template", &[None, Some(3)])?;
        let nv = v_template.shape[0];
        if nv == 0 {
            return Err(ar.invalid("v_template", "has no vertices"));
        }
        let f = ar.read("f", &[None, Some(3)])?;
        let shapedirs = ar.read("shapedirs", &[Some(nv), Some(3), None])?;
        let posedirs = ar.read("posedirs", &[Some(nv), Some(3), Some(POSE_FEATURES as u64)])?;
        let j_regressor = ar.read("J_regressor", &[Some(NUM_JOINTS as u64), Some(nv)])?;
        let weights = ar.read("weights", &[Some(nv), Some(NUM_JOINTS as u64)])?;
        let kintree = ar.read("kintree_table", &[Some(2), Some(NUM_JOINTS as u64)])?;
        let uvs = read_uvs(&mut ar, f.shape[0])?;

        let faces = f
            .data
            .chunks_exact(3)
            .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
            .collect::<Vec<_>>();
        if let Some((i, bad)) = f
            .data
            .iter()
            .enumerate()
            .find(|(_, &x)| x < 0.0 || x >= nv as f64)
        {
            return Err(ar.invalid(
                "f",
                format!("face index {bad} at flat index {i} is outside 0..{nv}"),
            ));
        }
        for j in 1..NUM_JOINTS {
            let parent = kintree.data[j];
            let expected = PARENTS[j].unwrap_or(0) as f64;
            if parent != expected {
                return Err(ar.invalid(
                    "kintree_table",
                    format!("joint {j} has parent {parent}, expected the SMPL-X parent {expected}"),
                ));
            }
        }
        let num_dirs = shapedirs.shape[2] as usize;
        let (shape_cols, expression_cols) = if num_dirs >= 400 {
            (0..300, 300..400)
        } else {
            (0..num_dirs.min(10), num_dirs.min(10)..num_dirs.min(20))
        };
        let posedirs = posedirs
            .data
            .iter()
            .any(|&x| x != 0.0)
            .then(|| posedirs.data.iter().map(|&x| x as f32).collect());
        let j_regressor = sparse_rows(&j_regressor.data, nv as usize);
        let skin_weights = sparse_rows(&weights.data, NUM_JOINTS);
        if let Some((v, _)) = skin_weights
            .iter()
            .enumerate()
            .find(|(_, row)| row.is_empty())
        {
            return Err(ar.invalid("weights", format!("vertex {v} has no skin weight")));
        }
        Ok(Self {
            source: ar.path().to_owned(),
            v_template: v_template
                .data
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect(),
            faces,
            dirs: shapedirs.data,
            num_dirs,
            shape_cols,
            expression_cols,
            posedirs,
            j_regressor,
            skin_weights,
            uvs,
            marker_ids: Default::default(),
        })
    }

    /// The [`NUM_MARKERS`](super::NUM_MARKERS) marker vertices of the motion model, by
    /// farthest-point sampling of the rest template
    /// ([`farthest_point_markers`](super::farthest_point_markers)). They depend on the
    /// template alone, not on a body's shape: chosen once per loaded model (about 1 ms for
    /// SMPL-X's 10 475 vertices), then shared by every body shaped from it.
    pub(crate) fn marker_ids(&self) -> &[u32] {
        self.marker_ids
            .get_or_init(|| super::farthest_point_markers(self, super::NUM_MARKERS))
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.v_template.len()
    }
    /// Number of shape coefficients (betas) the model accepts.
    pub fn num_betas(&self) -> usize {
        self.shape_cols.len()
    }
    /// Number of expression coefficients the model accepts.
    pub fn num_expression(&self) -> usize {
        self.expression_cols.len()
    }
    /// Whether the model has non-zero pose correctives.
    pub fn has_pose_correctives(&self) -> bool {
        self.posedirs.is_some()
    }
}

/// `vt` and `ft` together or neither; `ft` one row per face, every index inside `vt`.
fn read_uvs<R: std::io::Read + std::io::Seek>(
    ar: &mut ModelArchive<R>,
    num_faces: u64,
) -> Result<Option<BodyUvs>, ModelFileError> {
    let vt = ar.read_optional("vt", &[None, Some(2)])?;
    let ft = ar.read_optional("ft", &[Some(num_faces), Some(3)])?;
    let (vt, ft) = match (vt, ft) {
        (None, None) => return Ok(None),
        (Some(vt), Some(ft)) => (vt, ft),
        (Some(_), None) => {
            return Err(ar.invalid("ft", "is missing while `vt` is there (UVs need both)"))
        }
        (None, Some(_)) => {
            return Err(ar.invalid("vt", "is missing while `ft` is there (UVs need both)"))
        }
    };
    let n = vt.shape[0];
    if let Some((i, bad)) = ft
        .data
        .iter()
        .enumerate()
        .find(|(_, &x)| x < 0.0 || x >= n as f64 || x.fract() != 0.0)
    {
        return Err(ar.invalid(
            "ft",
            format!("UV index {bad} at flat index {i} is not an index into `vt` (0..{n})"),
        ));
    }
    Ok(Some(BodyUvs {
        coords: vt
            .data
            .chunks_exact(2)
            .map(|c| [c[0] as f32, c[1] as f32])
            .collect(),
        faces: ft
            .data
            .chunks_exact(3)
            .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
            .collect(),
    }))
}

fn sparse_rows(dense: &[Real], cols: usize) -> Vec<SparseRow> {
    dense
        .chunks_exact(cols)
        .map(|row| {
            row.iter()
                .enumerate()
                .filter(|(_, &w)| w != 0.0)
                .map(|(i, &w)| (i as u32, w))
                .collect()
        })
        .collect()
}
