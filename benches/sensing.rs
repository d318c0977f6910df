//! Sensing and collision costs, and the resolution knobs as trades (time vs error), in one run:
//! `cargo bench --bench sensing`. Results are written up in docs/SCENES.md.
//!
//! Plain timing harness (medians of repeated runs): the 3D SDF builds take seconds each, too
//! slow for criterion's sampling.

mod common;
use common::median_s;

use std::path::Path;
use std::time::Instant;

use egogen::body::{BodyModel, BodyParams};
use egogen::math::Vec3;
use egogen::scene::mesh_distance::MeshDistance;
use egogen::scene::{
    load_scene, sample_start_goals, scenario, sdf_penetration, walkable_map, Obstacle2,
    ScenarioKind, SceneMesh, SceneSdf, WalkableSettings,
};
use egogen::sensing::{DepthImage, EgoPose2, EgoSensor, LocalMap, RayScan, SensingWorld};
use glam::DVec2;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("assets/scenes/apartment.glb");
    let mesh = load_scene(&path, Default::default()).unwrap();
    let map = walkable_map(&mesh, &path, WalkableSettings::default()).unwrap();
    let starts = sample_start_goals(&map, 1, 2000, 0.2, 0.5);
    let poses: Vec<EgoPose2> = starts
        .iter()
        .map(|s| EgoPose2 {
            position: s.start,
            heading_rad: (s.goal - s.start).to_angle(),
        })
        .collect();
    let scan = RayScan::default();

    println!(
        "## Ray sensing (apartment, 0.1 m cells, 32 rays × 7 m, {} poses)",
        poses.len()
    );
    let world = SensingWorld {
        map: &map,
        obstacles: &[],
    };
    let one_core = median_s(
        || {
            let mut acc = 0.0f32;
            for p in &poses {
                acc += scan.observe(&world, *p).iter().sum::<f32>();
            }
            std::hint::black_box(acc);
        },
        15,
    );
    let rays = (poses.len() * 32) as f64;
    println!(
        "| static map, 1 core | {:.2} M rays/s |",
        rays / one_core / 1e6
    );
    let agents: Vec<Obstacle2> = (0..8)
        .map(|k| Obstacle2::Box {
            centre: poses[k * 7].position + DVec2::new(0.5, 0.0),
            half_extents: DVec2::new(0.25, 0.15),
            yaw_rad: k as f64,
        })
        .collect();
    let world_dyn = SensingWorld {
        map: &map,
        obstacles: &agents,
    };
    let dyn_core = median_s(
        || {
            for p in &poses {
                std::hint::black_box(scan.observe(&world_dyn, *p));
            }
        },
        15,
    );
    println!(
        "| + 8 agent boxes, 1 core | {:.2} M rays/s |",
        rays / dyn_core / 1e6
    );
    let batch = median_s(
        || {
            std::hint::black_box(scan.observe_batch(&world, &poses));
        },
        15,
    );
    println!(
        "| static map, batch API (rayon, {} threads) | {:.2} M rays/s |",
        rayon::current_num_threads(),
        rays / batch / 1e6
    );
    let lm = LocalMap::default();
    let lm_t = median_s(
        || {
            for p in &poses {
                std::hint::black_box(lm.observe(&world, *p));
            }
        },
        15,
    );
    println!(
        "| local map 16×16, 1 core | {:.2} µs per observation |",
        lm_t / poses.len() as f64 * 1e6
    );
    let depth = DepthImage::default();
    let depth_t = median_s(
        || {
            for p in &poses {
                std::hint::black_box(depth.observe(&world, *p));
            }
        },
        15,
    );
    println!(
        "| depth image 16×32 (Table 3's ablation), 1 core | {:.2} µs per observation ({:.2}× the 32 rays' {:.2} µs) |",
        depth_t / poses.len() as f64 * 1e6,
        depth_t / one_core,
        one_core / poses.len() as f64 * 1e6
    );

    println!("\n## Walkable map + 2D SDF: cell size trade (build on the apartment; error on a box rotated 30°)");
    let mut rotated = scenario(ScenarioKind::EmptyFloor).mesh;
    let mut tmp = SceneMesh::default();
    tmp.add_box("box", Vec3::new(-0.6, -0.4, 0.0), Vec3::new(0.6, 0.4, 1.0));
    let r = glam::DMat3::from_rotation_z(std::f64::consts::FRAC_PI_6);
    let verts: Vec<Vec3> = tmp.vertices.iter().map(|v| r * *v).collect();
    rotated.add_object("box", &verts, &tmp.triangles);
    println!("| cell (m) | apartment build (ms) | max 2D SDF error near box (m) |");
    for cell in [0.2, 0.1, 0.05, 0.025] {
        let s = WalkableSettings {
            cell_m: cell,
            ..Default::default()
        };
        let t = median_s(
            || {
                std::hint::black_box(walkable_map(&mesh, &path, s).unwrap());
            },
            5,
        );
        let m = walkable_map(&rotated, Path::new("rotated"), s).unwrap();
        let mut worst: f64 = 0.0;
        for j in 0..m.ny {
            for i in 0..m.nx {
                let c = m.centre(i, j);
                if c.length() > 3.0 {
                    continue;
                }
                let local = glam::DMat2::from_angle(-std::f64::consts::FRAC_PI_6) * c;
                let q = local.abs() - DVec2::new(0.6, 0.4);
                let truth = q.max(DVec2::ZERO).length() + q.max_element().min(0.0);
                worst = worst.max((m.sdf_m[j * m.nx + i] - truth).abs());
            }
        }
        println!("| {cell} | {:.1} | {worst:.4} |", t * 1e3);
    }

    println!("\n## 3D SDF: voxel size trade (apartment)");
    let md = MeshDistance::new(&mesh).unwrap();
    let (closed, all) = md.closed_triangles();
    println!(
        "(penetrable: {closed} of {all} triangles belong to closed, consistently wound parts)"
    );
    let probes: Vec<Vec3> = (0..3000u64)
        .map(|n| {
            let u = |s: u64| ((n * 3 + s) as f64 * 0.6180339887498949).fract();
            let (lo, hi) = mesh.bounds().unwrap();
            lo + (hi - lo) * Vec3::new(u(0), u(1), u(2))
        })
        .collect();
    let exact: Vec<f64> = probes.iter().map(|p| md.signed_distance(*p)).collect();
    println!("| voxel (m) | voxels | build (s, {} threads) | mean / max interpolation error (m) | memory (MB) |", rayon::current_num_threads());
    let mut sdf_005 = None;
    for voxel in [0.2, 0.1, 0.05] {
        let s = Instant::now();
        let sdf = SceneSdf::build(&mesh, voxel, 0.2).unwrap();
        let t = s.elapsed().as_secs_f64();
        let errs: Vec<f64> = probes
            .iter()
            .zip(&exact)
            .map(|(p, e)| (sdf.sample(*p) - e).abs())
            .collect();
        let mean = errs.iter().sum::<f64>() / errs.len() as f64;
        let max = errs.iter().copied().fold(0.0, f64::max);
        println!(
            "| {voxel} | {} | {t:.2} | {mean:.4} / {max:.4} | {:.1} |",
            sdf.values_m.len(),
            sdf.values_m.len() as f64 * 4.0 / 1e6
        );
        if voxel == 0.05 {
            sdf_005 = Some(sdf);
        }
    }
    let sdf = sdf_005.unwrap();

    println!("\n## Penetration query (13 380 body vertices, 0.05 m SDF)");
    let model = BodyModel::load(root.join("assets/body/SMPLX_NEUTRAL.npz")).unwrap();
    let mut params = BodyParams::default();
    params.set_joint_axis_angle(0, Vec3::new(std::f64::consts::FRAC_PI_2, 0.0, 0.0));
    let rest = model.rest_joints(&[], &[]).unwrap()[0];
    params.transl = Vec3::new(poses[0].position.x, poses[0].position.y, rest.y) - rest;
    let body = model.pose(&params).unwrap();
    let q = median_s(
        || {
            std::hint::black_box(sdf_penetration(&sdf, &body.vertices));
        },
        50,
    );
    let exact_t = median_s(
        || {
            std::hint::black_box(
                body.vertices
                    .iter()
                    .filter(|v| md.signed_distance(**v) < 0.0)
                    .count(),
            );
        },
        3,
    );
    println!("| SDF lookup (trilinear) | {:.1} µs per body |", q * 1e6);
    println!(
        "| exact mesh distance per vertex (BVH) | {:.1} µs per body ({:.0}× slower) |",
        exact_t * 1e6,
        exact_t / q
    );
}
