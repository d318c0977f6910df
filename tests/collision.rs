//! Scene SDF and penetration against brute force: exact mesh distance vs analytic shapes, the
//! voxel field vs exact values, penetration counts vs an exact inside test, the 2D box rule.

use egogen::body::{BodyModel, BodyParams};
use egogen::math::{axis_angle_to_matrix, Vec3};
use egogen::scene::mesh_distance::MeshDistance;
use egogen::scene::{
    blocked_cells_in_box, scenario, sdf_penetration, walkable_map, ScenarioKind, SceneMesh,
    SceneSdf, WalkableSettings,
};
use glam::DVec2;
use proptest::prelude::*;

/// A floor (16 m) and a floating 0.8 m cube rotated by 30° about z, centre (0.5, 0, 0.6).
fn scene() -> (SceneMesh, glam::DMat3, Vec3, Vec3) {
    let sc = scenario(ScenarioKind::EmptyFloor);
    let mut mesh = sc.mesh;
    let rot = axis_angle_to_matrix(Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_6));
    let centre = Vec3::new(0.5, 0.0, 0.6);
    let half = Vec3::splat(0.4);
    let mut tmp = SceneMesh::default();
    tmp.add_box("cube", -half, half);
    let verts: Vec<Vec3> = tmp.vertices.iter().map(|v| rot * *v + centre).collect();
    mesh.add_object("cube", &verts, &tmp.triangles);
    (mesh, rot, centre, half)
}

/// Analytic closest-feature signed distance: the open floor plane (no inside: |z|) or the
/// closed cube (negative inside).
fn reference(p: Vec3, rot: glam::DMat3, centre: Vec3, half: Vec3) -> f64 {
    let local = rot.transpose() * (p - centre);
    let q = local.abs() - half;
    let cube = q.max(Vec3::ZERO).length() + q.max_element().min(0.0);
    let floor = p.z.abs();
    if cube.abs() < floor {
        cube
    } else {
        floor
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn exact_mesh_distance_matches_analytic(x in -2.0f64..3.0, y in -2.0f64..2.0, z in -1.0f64..2.0) {
        let (mesh, rot, centre, half) = scene();
        let md = MeshDistance::new(&mesh).unwrap();
        let p = Vec3::new(x, y, z);
        let (got, want) = (md.signed_distance(p), reference(p, rot, centre, half));
        prop_assert!((got - want).abs() < 1e-9, "{p:?}: {got} vs {want}");
    }
}

#[test]
fn voxel_sdf_matches_exact_and_interpolates_within_half_a_voxel() {
    let (mesh, rot, centre, half) = scene();
    // Crop the floor to keep the grid small: a 3 m patch around the cube.
    let mut crop = SceneMesh::default();
    let f = [
        Vec3::new(-1.0, -1.5, 0.0),
        Vec3::new(2.0, -1.5, 0.0),
        Vec3::new(2.0, 1.5, 0.0),
        Vec3::new(-1.0, 1.5, 0.0),
    ];
    crop.add_object("floor", &f, &[[0, 1, 2], [0, 2, 3]]);
    let cube_tris: Vec<[u32; 3]> = mesh.triangles[2..]
        .iter()
        .map(|t| t.map(|i| i - 4))
        .collect();
    crop.add_object("cube", &mesh.vertices[4..], &cube_tris);
    let voxel = 0.05;
    let sdf = SceneSdf::build(&crop, voxel, 0.2).unwrap();
    let mut worst_centre: f64 = 0.0;
    for k in 0..sdf.dims[2] {
        for j in (0..sdf.dims[1]).step_by(3) {
            for i in (0..sdf.dims[0]).step_by(3) {
                let p = sdf.origin + Vec3::new(i as f64, j as f64, k as f64) * voxel;
                if !(-1.0..=2.0).contains(&p.x) || p.y.abs() > 1.5 {
                    continue; // beyond the cropped floor's rim the analytic plane does not apply
                }
                worst_centre =
                    worst_centre.max((sdf.sample(p) - reference(p, rot, centre, half)).abs());
            }
        }
    }
    let mut worst_between: f64 = 0.0;
    for n in 0..20_000u64 {
        let u = |s: u64| ((n * 3 + s) as f64 * 0.6180339887498949).fract();
        let p = Vec3::new(-0.9 + 2.7 * u(0), -1.3 + 2.6 * u(1), -0.15 + 1.3 * u(2)); // inside the grid
        worst_between = worst_between.max((sdf.sample(p) - reference(p, rot, centre, half)).abs());
    }
    eprintln!("3D SDF ({voxel} m voxels): max error at voxel centres {worst_centre:.2e} m, between centres {worst_between:.4} m");
    assert!(worst_centre < 1e-5);
    assert!(worst_between <= 0.5 * voxel, "{worst_between}");
}

#[test]
fn penetration_counts_match_exact_inside_test() {
    let (mut mesh, rot, centre, half) = scene();
    mesh.vertices.truncate(4);
    mesh.triangles.truncate(2);
    mesh.triangle_object.truncate(2);
    mesh.objects.truncate(1);
    // Replace the 16 m floor by a 3 m patch, then add the cube again.
    for v in &mut mesh.vertices {
        *v = Vec3::new(v.x.signum() * 1.5 + 0.5, v.y.signum() * 1.5, 0.0);
    }
    let mut tmp = SceneMesh::default();
    tmp.add_box("cube", -half, half);
    let verts: Vec<Vec3> = tmp.vertices.iter().map(|v| rot * *v + centre).collect();
    mesh.add_object("cube", &verts, &tmp.triangles);
    let voxel = 0.04;
    let sdf = SceneSdf::build(&mesh, voxel, 0.2).unwrap();

    let model = BodyModel::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/body/SMPLX_NEUTRAL.npz"
    ))
    .unwrap();
    let mut params = BodyParams::default();
    // Stand up in the z-up world (rotate +90° about x) with the right side inside the cube.
    params.set_joint_axis_angle(0, Vec3::new(std::f64::consts::FRAC_PI_2, 0.0, 0.0));
    let rest = model.rest_joints(&[], &[]).unwrap()[0];
    params.transl = Vec3::new(0.1, 0.0, rest.y) - rest;
    let body = model.pose(&params).unwrap();
    let pen = sdf_penetration(&sdf, &body.vertices);
    let mut exact = 0usize;
    let mut near_surface = 0usize;
    let mut disagreements = 0usize;
    for v in &body.vertices {
        let d = reference(*v, rot, centre, half);
        let inside = d < 0.0;
        exact += inside as usize;
        if d.abs() < voxel {
            near_surface += 1;
        }
        if inside != (sdf.sample(*v) < 0.0) {
            disagreements += 1;
            assert!(
                d.abs() < voxel,
                "a vertex {d} m from the surface was misclassified"
            );
        }
    }
    eprintln!(
        "penetration: SDF count {} (sum {:.3} m) vs exact {exact}; {disagreements} disagreements, all among {near_surface} vertices within one voxel ({voxel} m) of the surface",
        pen.count, pen.sum_negative_m
    );
    assert!(exact > 100, "the test body must penetrate: {exact}");
    assert!(pen.sum_negative_m < 0.0);
}

#[test]
fn box_rule_counts_blocked_cells() {
    let sc = scenario(ScenarioKind::SingleBox); // 1 m box at the origin
    let map = walkable_map(
        &sc.mesh,
        std::path::Path::new("single_box"),
        WalkableSettings::default(),
    )
    .unwrap();
    // A 0.4 × 0.2 m body box straddling the box's east face (x = 0.5): cells with centres at
    // x = 0.35, 0.45 (inside) × y = −0.05, 0.05 → 4 blocked cells.
    assert_eq!(
        blocked_cells_in_box(&map, DVec2::new(0.5, 0.0), DVec2::new(0.2, 0.1), 0.0),
        4
    );
    assert_eq!(
        blocked_cells_in_box(&map, DVec2::new(2.0, 0.0), DVec2::new(0.2, 0.1), 0.0),
        0
    );
    // Rotated by 90°, the long side runs along y: centres x = 0.45 only.
    assert_eq!(
        blocked_cells_in_box(
            &map,
            DVec2::new(0.5, 0.0),
            DVec2::new(0.2, 0.1),
            std::f64::consts::FRAC_PI_2
        ),
        4
    );
}

#[test]
fn inward_wound_parts_are_flipped_and_open_parts_have_no_inside() {
    let mut tmp = SceneMesh::default();
    tmp.add_box("cube", Vec3::splat(-0.5), Vec3::splat(0.5));
    let centre = Vec3::ZERO;
    // Inward winding: same cube, every triangle reversed.
    let mut inward = SceneMesh::default();
    let flipped: Vec<[u32; 3]> = tmp.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
    inward.add_object("inward", &tmp.vertices, &flipped);
    assert!((MeshDistance::new(&inward).unwrap().signed_distance(centre) + 0.5).abs() < 1e-12);
    assert!((MeshDistance::new(&tmp).unwrap().signed_distance(centre) + 0.5).abs() < 1e-12);
    // Open: drop the top face (2 triangles) — no inside any more.
    let mut open = SceneMesh::default();
    open.add_object("open", &tmp.vertices, &tmp.triangles[..10]);
    assert!((MeshDistance::new(&open).unwrap().signed_distance(centre) - 0.5).abs() < 1e-12);
}
