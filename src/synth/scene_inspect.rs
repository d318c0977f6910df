//! `egogen scene inspect`'s job: a scene loaded, its walkable map built and summarised (with
//! its places to sit), and a PNG of the map with sampled starts, goals and their sensing rays
//! (and, when asked, each start's egocentric depth image beside it). Here because it draws
//! (`preview`) what the walker senses (`sensing`) in a scene, which `scene` may not use.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::preview::map::AGENT_COLOURS;
use crate::preview::raster::RgbImage;
use crate::sensing::DepthImage;

/// Prints the summary of `scene` (a file, or `scenario:NAME`, read as `frame` says) and draws its map with `agents`
/// sampled start/goal pairs (from `seed`) and their rays to `out`; with `depth_images`, each
/// start's egocentric depth image (Table 3's ablation, looking at its goal) to the right of
/// the map, framed in the colour of its start.
#[allow(clippy::too_many_arguments)]
pub(crate) fn scene_inspect(
    scene: &str,
    frame: crate::scene::SceneFrame,
    settings: crate::scene::WalkableSettings,
    out: &Path,
    agents: usize,
    seed: u64,
    depth_images: bool,
) -> Result<()> {
    use crate::preview::map::MapPicture;
    use crate::scene::{sample_start_goals, walkable_map};
    use crate::sensing::{EgoPose2, RayScan, SensingWorld};

    let cell_m = settings.cell_m;
    if !(cell_m.is_finite() && cell_m > 0.0) {
        bail!("--cell-m must be a positive number of metres, got {cell_m}");
    }
    if let Some((field, what)) = settings.floor_problem() {
        bail!("--{}: {what}", field.replace('_', "-"));
    }
    let (mesh, moving, path) = inspected_scene(scene, frame)?;
    let t = std::time::Instant::now();
    let map = walkable_map(&mesh, &path, settings)?;
    let build_s = t.elapsed().as_secs_f64();
    let (lo, hi) = mesh.bounds().expect("non-empty scene");
    let components = map.component.iter().copied().max().unwrap_or(0);
    println!("scene:      {}", path.display());
    println!(
        "objects:    {} ({} triangles)",
        mesh.objects.len(),
        mesh.triangles.len()
    );
    println!(
        "bounds:     ({:.2}, {:.2}, {:.2}) .. ({:.2}, {:.2}, {:.2}) m",
        lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
    );
    match map.floor_range(|k| map.has_floor[k]) {
        Some((lo, hi)) if !map.is_flat() => println!(
            "floor:      z = {:.3} m, stepped floors from {lo:.3} to {hi:.3} m",
            map.floor_z_m
        ),
        _ => println!("floor:      z = {:.3} m", map.floor_z_m),
    }
    if let Some(warning) = crate::scene::scene_frame_warning(&mesh, &map, &path) {
        eprintln!("{warning}");
    }
    println!(
        "grid:       {} x {} cells of {} m (built in {:.3} s)",
        map.nx, map.ny, map.cell_m, build_s
    );
    println!(
        "walkable:   {} cells = {:.1} m², {} connected region(s)",
        map.walkable_count(),
        map.walkable_count() as f64 * cell_m * cell_m,
        components
    );
    let seats = crate::scene::find_seats(&mesh, &map, &crate::scene::SeatSettings::default());
    print_seats(&seats);
    let obstacles: Vec<_> = moving.iter().map(|m| m.at(0.0)).collect();
    let world = SensingWorld {
        map: &map,
        obstacles: &obstacles,
    };
    let scan = RayScan::default();
    let mut pic = MapPicture::new(&map, 900);
    for o in &obstacles {
        pic.obstacle(o, [200, 60, 40]);
    }
    for s in &seats {
        pic.line(s.pelvis(), s.stand(), [240, 170, 0]);
        pic.dot(s.pelvis(), 5, [240, 170, 0]);
    }
    let depth = DepthImage::default();
    let mut pictures = Vec::new();
    for (k, sg) in sample_start_goals(&map, seed, agents, 0.3, 1.0)
        .into_iter()
        .enumerate()
    {
        let heading = (sg.goal - sg.start).to_angle();
        let pose = EgoPose2 {
            position: sg.start,
            heading_rad: heading,
        };
        for (k, d) in scan.distances(&world, pose).into_iter().enumerate() {
            let end = pose.position + scan.beam_dir(pose, k) * d;
            let colour = if d < scan.settings.max_range_m {
                [220, 90, 30]
            } else {
                [80, 160, 80]
            };
            pic.line(pose.position, end, colour);
        }
        let start_colour = if depth_images {
            AGENT_COLOURS[k % AGENT_COLOURS.len()]
        } else {
            [30, 80, 200]
        };
        pic.dot(sg.start, 4, start_colour);
        pic.dot(sg.goal, 4, [200, 30, 160]);
        if depth_images {
            pictures.push(depth_picture(
                &depth,
                &depth.ranges(&world, pose),
                start_colour,
            ));
        }
    }
    let image = if depth_images {
        let cell = pictures.iter().map(|p| p.width).max().unwrap_or(1) + 16;
        let column = RgbImage::contact_sheet(&pictures, cell, 1, [255, 255, 255]);
        pic.image.hconcat(&column, [255, 255, 255])
    } else {
        pic.image
    };
    image.write_png(out)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The scene `scene` names (a file, `dwelling:SEED` or `scenario:NAME`, read as `frame` says):
/// its mesh, its moving obstacles and its path.
fn inspected_scene(
    scene: &str,
    frame: crate::scene::SceneFrame,
) -> Result<(
    crate::scene::SceneMesh,
    Vec<crate::scene::MovingObstacle>,
    PathBuf,
)> {
    use crate::scene::{load_scene, scenario, ScenarioKind};
    Ok(match scene.strip_prefix("scenario:") {
        Some(name) => {
            let kind: ScenarioKind = serde_json::from_value(serde_json::Value::String(name.into()))
                .map_err(|_| anyhow::anyhow!("unknown scenario `{name}` (expected empty_floor, single_box or moving_box)"))?;
            let sc = scenario(kind);
            (sc.mesh, sc.moving, PathBuf::from(scene))
        }
        None => {
            let path = crate::scene::dwelling::scene_source(scene, Path::new(""))
                .map_err(|m| anyhow::anyhow!("{m}"))?;
            (load_scene(&path, frame)?, Vec::new(), path)
        }
    })
}

/// Prints the places to sit found, one line each.
fn print_seats(seats: &[crate::scene::Seat]) {
    println!(
        "seats:      {} place(s) to sit on {} object(s) ({} named as seats)",
        seats.len(),
        seats
            .iter()
            .map(|s| s.object)
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        seats
            .iter()
            .filter(|s| s.naming == crate::scene::seats::SeatNaming::Named)
            .count()
    );
    for s in seats {
        println!(
            "            {:<28} seat {:.2} m at ({:.2}, {:.2}), facing {:>4.0}°, {}{}",
            s.object_name,
            s.height_m,
            s.pelvis_xy[0],
            s.pelvis_xy[1],
            s.facing_rad.to_degrees(),
            if s.backed { "backed" } else { "no back" },
            s.pull.as_ref().map_or(String::new(), |p| {
                let m = |p: &crate::scene::chair_pull::Pull| {
                    glam::DVec2::from_array(p.offset_m).length()
                };
                let longer = s.longer.as_ref().and_then(|l| l.pull.as_ref());
                format!(
                    ", pulled out {:.2} m{}",
                    m(p),
                    longer.map_or(String::new(), |l| format!(
                        " ({:.2} m where a body needs more room)",
                        m(l)
                    ))
                )
            })
        );
    }
}

/// A depth image as grey levels (near bright, nothing within range black), each pixel 8 × 8,
/// framed 3 px wide in `frame`.
fn depth_picture(depth: &DepthImage, ranges: &[f64], frame: [u8; 3]) -> RgbImage {
    const SCALE: usize = 8;
    const BORDER: usize = 3;
    let s = depth.settings();
    let (w, h) = (s.cols * SCALE + 2 * BORDER, s.rows * SCALE + 2 * BORDER);
    let mut image = RgbImage::new(w, h, frame);
    for y in 0..s.rows * SCALE {
        for x in 0..s.cols * SCALE {
            let range = ranges[(y / SCALE) * s.cols + x / SCALE];
            let grey = (255.0 * (1.0 - range / s.max_range_m))
                .round()
                .clamp(0.0, 255.0) as u8;
            image.pixels[(y + BORDER) * w + x + BORDER] = [grey; 3];
        }
    }
    image
}
