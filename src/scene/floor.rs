//! Floor height: the lowest large upward-facing horizontal surface.

use super::mesh::SceneMesh;

/// Upward-facing means a unit normal with z above this.
pub(crate) const UP_FACING_MIN_NZ: f64 = 0.95;

/// Floor height (m): area-weighted histogram (1 cm bins) of upward-facing triangles; the
/// lowest bin holding at least a quarter of the largest bin's area. `None` if nothing faces up.
pub(crate) fn detect_floor_z(mesh: &SceneMesh) -> Option<f64> {
    let mut bins: std::collections::BTreeMap<i64, (f64, f64)> = Default::default();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let n = (b - a).cross(c - a);
        let area2 = n.length();
        if area2 <= 0.0 || n.z / area2 < UP_FACING_MIN_NZ {
            continue;
        }
        let z = (a.z + b.z + c.z) / 3.0;
        let e = bins.entry((z * 100.0).floor() as i64).or_default();
        e.0 += area2;
        e.1 += area2 * z;
    }
    let max_area = bins.values().map(|b| b.0).fold(0.0, f64::max);
    let (_, (area, weighted_z)) = bins.into_iter().find(|(_, (a, _))| *a >= 0.25 * max_area)?;
    Some(weighted_z / area)
}
