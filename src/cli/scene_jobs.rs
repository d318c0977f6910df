//! `egogen scene inspect`: a scene loaded, its walkable map built and summarised, and a PNG of
//! the map with sampled starts, goals and their sensing rays (and, when asked, each start's
//! egocentric depth image beside it). `egogen scene generate`: dwellings generated, written and
//! summarised (`--summary`, read by `tools/dwelling_survey.py`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use crate::preview::map::AGENT_COLOURS;
use crate::preview::raster::RgbImage;
use crate::sensing::DepthImage;

/// How a scene file named on the command line is read: `--up y|z` (none: the format's default)
/// and `--unit-m` (metres per unit of the file; none: 1), checked.
pub fn scene_frame_flags(
    up: Option<&str>,
    unit_m: Option<f64>,
) -> Result<crate::scene::SceneFrame> {
    let up = match up {
        None => None,
        Some(name) => Some(
            crate::scene::UpAxis::from_name(name)
                .ok_or_else(|| anyhow::anyhow!("--up: expected y or z, got `{name}`"))?,
        ),
    };
    crate::scene::SceneFrame::new(up, unit_m).map_err(|m| anyhow::anyhow!("--unit-m: {m}"))
}

/// Prints the summary of `scene` (a file, or `scenario:NAME`, read as `frame` says) and draws its map with `agents`
/// sampled start/goal pairs (from `seed`) and their rays to `out`; with `depth_images`, each
/// start's egocentric depth image (Table 3's ablation, looking at its goal) to the right of
/// the map, framed in the colour of its start.
#[allow(clippy::too_many_arguments)]
pub fn scene_inspect(
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
            "            {:<28} seat {:.2} m at ({:.2}, {:.2}), facing {:>4.0}°, {}",
            s.object_name,
            s.height_m,
            s.pelvis_xy[0],
            s.pelvis_xy[1],
            s.facing_rad.to_degrees(),
            if s.backed { "backed" } else { "no back" }
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

/// `egogen scene generate`'s flags.
#[derive(clap::Args, Debug)]
pub struct GenerateArgs {
    /// Seed of the (first) dwelling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Dwellings to make, from seeds --seed, --seed + 1, …
    #[arg(long, default_value_t = 1)]
    pub count: u64,
    /// Folder to write into (its dwelling files must not exist).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Generate and check only, write nothing (to measure generation).
    #[arg(long, conflicts_with = "out")]
    pub check_only: bool,
    /// TOML file of generator settings (keys of docs/SCENES.md "Generated dwellings"; every
    /// key optional).
    #[arg(long)]
    pub settings: Option<PathBuf>,
    /// Furniture catalogue folder (default: the shipped CC0 one, assets/furniture).
    #[arg(long)]
    pub catalogue: Option<PathBuf>,
    /// Also write one JSON line per dwelling here (seed, seconds, tries, rooms, area, pieces,
    /// models, seats, seating pieces with and without a seat found): `tools/dwelling_survey.py`
    /// reads it.
    #[arg(long)]
    pub summary: Option<PathBuf>,
}

/// Reads and checks a dwelling settings file (`scene generate --settings`); errors name the
/// file and the key.
pub fn load_dwelling_settings(path: &Path) -> Result<crate::scene::dwelling::DwellingSettings> {
    let settings: crate::scene::dwelling::DwellingSettings =
        crate::cli::config_file::load_toml(path)?;
    if let Some((key, message)) = settings.problem() {
        bail!("{}: `{key}`: {message}", path.display());
    }
    Ok(settings)
}

/// Generates `args.count` dwellings, writes them (unless checking only) and prints a line per
/// dwelling and a summary (time, rooms, area, objects, models, seats).
pub fn scene_generate(args: &GenerateArgs) -> Result<()> {
    use crate::scene::dwelling::{
        dwelling_files, generate, shipped_catalogue_dir, Catalogue, DwellingSettings,
    };
    let out = match (&args.out, args.check_only) {
        (Some(out), _) => Some(out.clone()),
        (None, true) => None,
        (None, false) => bail!("--out DIR is required (or --check-only to write nothing)"),
    };
    if args.count == 0 {
        bail!("--count must be at least 1");
    }
    let settings = match &args.settings {
        Some(path) => load_dwelling_settings(path)?,
        None => DwellingSettings::default(),
    };
    let catalogue_dir = args.catalogue.clone().unwrap_or_else(shipped_catalogue_dir);
    let catalogue = Catalogue::load(&catalogue_dir)?;
    let dir_of = |seed: u64| {
        out.as_ref().map(|o| {
            if args.count == 1 {
                o.clone()
            } else {
                o.join(format!("seed_{seed}"))
            }
        })
    };
    let last = args
        .seed
        .checked_add(args.count - 1)
        .ok_or_else(|| anyhow::anyhow!("--seed + --count overflows"))?;
    for seed in args.seed..=last {
        if let Some(dir) = dir_of(seed) {
            let (glb, json) = dwelling_files(&dir);
            for f in [glb, json] {
                crate::atomic_file::refuse_existing(&f)?;
            }
        }
    }
    if let Some(summary) = &args.summary {
        crate::atomic_file::refuse_existing(summary)?;
    }
    let bar = crate::progress::progress_bar(
        "egogen scene generate",
        "dwellings",
        "dwellings",
        args.count,
        0,
    );
    let mut times = Vec::new();
    let mut models = std::collections::BTreeSet::new();
    let mut lines = String::new();
    let mut failed = Vec::new();
    for seed in args.seed..=last {
        let t = std::time::Instant::now();
        let d = match generate(&settings, &catalogue, seed) {
            Ok(d) => d,
            Err(e @ crate::scene::dwelling::DwellingError::NoDwelling { .. }) if args.count > 1 => {
                bar.println(format!("seed {seed}: {e}"));
                failed.push(seed);
                bar.inc(1);
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        if let Some(dir) = dir_of(seed) {
            d.write(&catalogue, &dir)?;
        }
        let seconds = t.elapsed().as_secs_f64();
        if args.summary.is_some() {
            lines.push_str(&dwelling_summary_line(&d, seconds).to_string());
            lines.push('\n');
        }
        times.push(seconds);
        models.extend(d.placed.iter().map(|p| p.model.clone()));
        let area: f64 = d.plan.rooms.iter().map(|r| r.area_m2()).sum();
        let line = format!(
            "seed {seed}: {} rooms, {area:.1} m², {} pieces ({} models), {} seats, {} tries, {seconds:.2} s",
            d.plan.rooms.len(),
            d.placed.len(),
            d.placed.iter().map(|p| &p.model).collect::<std::collections::BTreeSet<_>>().len(),
            d.seats_per_room.iter().sum::<usize>(),
            d.tries
        );
        if args.count == 1 {
            println!("{line}");
        } else {
            bar.inc(1);
            bar.println(line);
        }
    }
    bar.finish_and_clear();
    if let Some(summary) = &args.summary {
        crate::atomic_file::write_atomically(summary, lines.as_bytes())
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", summary.display()))?;
    }
    if times.is_empty() {
        bail!("no dwelling could be made (seeds {failed:?})");
    }
    times.sort_by(f64::total_cmp);
    let q = |p: f64| times[((times.len() - 1) as f64 * p).round() as usize];
    println!(
        "{} dwellings: {:.2} s median, {:.2} s p95 each; {} catalogue models used",
        times.len(),
        q(0.5),
        q(0.95),
        models.len()
    );
    if let Some(o) = out {
        println!("written to {}", o.display());
    }
    if !failed.is_empty() {
        bail!(
            "{} of {} seeds made no dwelling: {failed:?}",
            failed.len(),
            args.count
        );
    }
    Ok(())
}

/// One dwelling's line of `--summary`.
fn dwelling_summary_line(d: &crate::scene::dwelling::Dwelling, seconds: f64) -> serde_json::Value {
    use crate::scene::dwelling::Role;
    let seating = [
        Role::Sofa,
        Role::Armchair,
        Role::DiningChair,
        Role::DeskChair,
        Role::Stool,
        Role::Bed,
    ];
    let (mut seating_with, mut seating_without, mut other_with, mut built_with) = (0, 0, 0, 0);
    for o in &d.objects {
        let seating = o.piece.map(|k| seating.contains(&d.placed[k].role));
        match (seating, o.seats > 0) {
            (Some(true), true) => seating_with += 1,
            (Some(true), false) => seating_without += 1,
            (Some(false), true) => other_with += 1,
            (None, true) => built_with += 1,
            _ => {}
        }
    }
    serde_json::json!({
        "seed": d.seed,
        "seconds": seconds,
        "tries": d.tries,
        "redrawn": d.redrawn,
        "rooms": d.plan.rooms.iter().map(|r| r.kind.name()).collect::<Vec<_>>(),
        "area_m2": d.plan.rooms.iter().map(|r| r.area_m2()).sum::<f64>(),
        "pieces": d.placed.len(),
        "models": d.placed.iter().map(|p| p.model.as_str()).collect::<Vec<_>>(),
        "roles": d.placed.iter().map(|p| format!("{:?}", p.role)).collect::<Vec<_>>(),
        "piece_rooms": d.placed.iter().map(|p| d.plan.rooms[p.room].kind.name()).collect::<Vec<_>>(),
        "seats": d.seats_per_room.iter().sum::<usize>(),
        "seating_with_seat": seating_with,
        "seating_without_seat": seating_without,
        "other_with_seat": other_with,
        "built_with_seat": built_with,
        "triangles": d.mesh.triangles.len(),
    })
}
