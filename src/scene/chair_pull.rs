//! Chairs pulled up to a table or a desk: their front has no free floor (it is under the
//! table), so [`super::seats::find_seats`] finds no place on them. Here such a chair is found
//! by its geometry — a surface at sitting height with a backrest above one side, which gives
//! its front — and pulled straight back, away from what it faces, until its seat has room
//! above it, the floor in front of it is free for a person to stand and sit down, and the
//! pulled chair stands on free floor. The place to sit is then on the pulled chair; the walk
//! ends at walkable floor beside it, from where the person steps in while the chair moves.
//! A second, longer pull of the same chair is kept where it works, for bodies too large for
//! the first (knees into the table, or standing up into it). A chair's places found the usual
//! way face where its backrest says (not sideways).

use glam::DVec2;

use super::floor::UP_FACING_MIN_NZ;
use super::mesh::{ObjectId, SceneMesh};
use super::object_class::ObjectClass;
use super::walkable::{clip_z, convex_overlaps_rect, WalkableMap};
use crate::math::Vec3;

/// What a chair needs of its place (from the seat finder's settings).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ChairNeeds {
    /// Lowest and highest seat surface over the floor (m).
    pub height_m: (f64, f64),
    /// Free space above the seat (m).
    pub headroom_m: f64,
    /// Half the width of a seat (m).
    pub min_half_width_m: f64,
    /// Free floor round where the walk ends (m to the nearest non-walkable cell).
    pub stand_clearance_m: f64,
}

/// How a chair is pulled out from its table to sit on.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct Pull {
    /// How far the chair moves from where the scene has it (horizontal, m).
    pub offset_m: [f64; 2],
    /// Map cells, in ascending order, free of everything but the chair, where the person
    /// steps in from the walk's end and stands to sit down (not walkable on the scene's map:
    /// the chair stands there until pulled).
    #[serde(skip)]
    pub free_cells: Vec<usize>,
}

impl Pull {
    /// Whether `p` lies on the floor the pulled chair leaves free to stand on.
    pub(crate) fn frees(&self, map: &WalkableMap, p: DVec2) -> bool {
        map.cell_of(p)
            .is_some_and(|(i, j)| self.free_cells.binary_search(&(j * map.nx + i)).is_ok())
    }
}

/// A place to sit on a chair pulled out.
#[derive(Debug, Clone)]
pub(crate) struct PulledChair {
    pub object: ObjectId,
    /// Where the seated pelvis goes on the pulled chair.
    pub pelvis: DVec2,
    pub facing: DVec2,
    /// World height of the seat surface (m).
    pub top_z: f64,
    /// Where the walk to it ends (walkable floor).
    pub stand: DVec2,
    /// How far the seat reaches in front of the pelvis (m).
    pub depth_m: f64,
    /// Map cells of the pulled chair's seat, in ascending order.
    pub cells: Vec<usize>,
    pub pull: Pull,
    /// The same chair pulled [`MORE_KNEE_ROOM_M`] farther or more, where that works too:
    /// tried when a body is too large for the shorter pull.
    pub longer: Option<Box<PulledChair>>,
}

/// Shortest pull that frees a chair (m).
const MIN_PULL_M: f64 = 0.2;

/// Farthest a chair is pulled out (m).
const MAX_PULL_M: f64 = 1.0;

/// How much farther a chair's second pull goes than its first (m): room for a body whose
/// knees would enter the table at the first, or that would stand up into it.
pub(crate) const MORE_KNEE_ROOM_M: f64 = 0.15;
/// The clips stand this far in front of where they sit (m, 0.3–0.45 in the shipped clips).
pub(crate) const STAND_IN_FRONT_M: f64 = 0.4;
/// Free floor round where the feet stand in front of the pulled chair (m).
const FEET_CLEARANCE_M: f64 = 0.15;
/// Farthest the walk to a pulled chair ends from where the person stands to sit (m): the
/// step in from the side.
pub(crate) const MAX_STEP_IN_M: f64 = 0.9;

/// A chair's seat and back, from its own triangles.
struct ChairShape {
    /// Height of the seat surface (world z).
    top_z: f64,
    /// Map cells of the seat surface, where the scene has the chair.
    cells: Vec<usize>,
    centre: DVec2,
    /// Unit vector from the backrest to the seat's centre: where a seated person faces.
    facing: DVec2,
    /// Map cells the chair occupies between step and head height.
    footprint: Vec<usize>,
    /// Those whose four neighbours it occupies too: what must be free where it is pulled to
    /// (a cell at its edge may be shared with a chair standing close beside it).
    inner: Vec<usize>,
    /// Its horizontal bounds.
    lo: DVec2,
    hi: DVec2,
}

/// Places to sit on chairs that must be pulled out first: every object that is not refused
/// by its name, is chair-shaped with a backrest, and is not in `found` (objects with a place
/// already); in object order.
pub(crate) fn pulled_out_chairs(
    mesh: &SceneMesh,
    map: &WalkableMap,
    settings: &ChairNeeds,
    found: &[ObjectId],
) -> Vec<PulledChair> {
    let mut seats = Vec::new();
    for (o, object) in mesh.objects.iter().enumerate() {
        // A chair is every object of its name (its parts); each name once.
        let parts = |p: &&super::mesh::SceneObject| p.name == object.name;
        let first = mesh.objects.iter().position(|p| parts(&p)) == Some(o);
        let refused =
            ObjectClass::named(&object.name, object.label.as_deref()).is_some_and(|c| !c.is_seat());
        if !first
            || refused
            || mesh
                .objects
                .iter()
                .filter(parts)
                .any(|p| found.contains(&p.id))
        {
            continue;
        }
        let Some(chair) = chair_shape(mesh, map, settings, &object.name) else {
            continue;
        };
        // Everything else near enough to matter: within reach of the pull, the feet and the
        // step in.
        let reach = MAX_PULL_M + STAND_IN_FRONT_M + MAX_STEP_IN_M + 0.7;
        let near: Vec<[Vec3; 3]> = (0..mesh.triangles.len())
            .filter(|&t| !of_name(mesh, t, &object.name))
            .map(|t| mesh.triangle(t))
            .filter(|v| {
                v.iter()
                    .any(|p| p.x >= chair.lo.x - reach && p.y >= chair.lo.y - reach)
                    && v.iter()
                        .any(|p| p.x <= chair.hi.x + reach && p.y <= chair.hi.y + reach)
            })
            .collect();
        let floor_band = map.floor_z_m + map.settings.stepped_over_m();
        let others = occupied(map, &near, None);
        let covers = occupied(
            map,
            &near,
            Some((chair.top_z + 0.15, chair.top_z + settings.headroom_m)),
        );
        let low = occupied(map, &near, Some((floor_band, chair.top_z)));
        let pulled = |min_m: f64| {
            let (stand, pull) = pull_out(map, settings, &chair, &others, &low, &covers, min_m)?;
            let offset = DVec2::from_array(pull.offset_m);
            let moved = |k: usize| {
                map.cell_of(map.centre(k % map.nx, k / map.nx) + offset)
                    .map(|(i, j)| j * map.nx + i)
            };
            let mut cells: Vec<usize> = chair.cells.iter().filter_map(|&k| moved(k)).collect();
            cells.sort_unstable();
            cells.dedup();
            let pelvis = chair.centre + offset;
            Some(PulledChair {
                object: object.id,
                pelvis,
                facing: chair.facing,
                top_z: chair.top_z,
                stand,
                depth_m: front_depth(map, &cells, pelvis, chair.facing),
                cells,
                pull,
                longer: None,
            })
        };
        let Some(mut seat) = pulled(MIN_PULL_M) else {
            continue;
        };
        let first_m = DVec2::from_array(seat.pull.offset_m).length();
        seat.longer = pulled(first_m + MORE_KNEE_ROOM_M).map(Box::new);
        seats.push(seat);
    }
    seats
}

/// Where a person sitting on the chair-shaped objects named `name` faces: away from its
/// backrest ([`chair_shape`]); `None` for anything else.
pub(crate) fn chair_facing(
    mesh: &SceneMesh,
    map: &WalkableMap,
    settings: &ChairNeeds,
    name: &str,
) -> Option<DVec2> {
    chair_shape(mesh, map, settings, name).map(|c| c.facing)
}

/// Whether triangle `t` belongs to an object named `name`.
fn of_name(mesh: &SceneMesh, t: usize, name: &str) -> bool {
    (mesh.triangle_object[t].0 as usize)
        .checked_sub(1)
        .and_then(|o| mesh.objects.get(o))
        .is_some_and(|o| o.name == name)
}

/// The seat and back of the objects named `name` (a chair's parts), if they are
/// chair-shaped: an upward surface at sitting height no larger than 0.8 m across, and
/// geometry of their own over one side of it.
fn chair_shape(
    mesh: &SceneMesh,
    map: &WalkableMap,
    settings: &ChairNeeds,
    name: &str,
) -> Option<ChairShape> {
    // The seat: the highest upward surface at sitting height over each cell.
    let mut top: Vec<(usize, f64)> = Vec::new();
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    let tris: Vec<[Vec3; 3]> = (0..mesh.triangles.len())
        .filter(|&t| of_name(mesh, t, name))
        .map(|t| mesh.triangle(t))
        .collect();
    for v in &tris {
        for p in v {
            lo = lo.min(DVec2::new(p.x, p.y));
            hi = hi.max(DVec2::new(p.x, p.y));
        }
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        if n.length() <= 0.0 || n.z / n.length() < UP_FACING_MIN_NZ {
            continue;
        }
        map.for_cells_under(*v, DVec2::ZERO, |k, z| {
            let h = z - map.cell_floor_m(k);
            if h >= settings.height_m.0 && h <= settings.height_m.1 {
                top.push((k, z));
            }
        });
    }
    let size = hi - lo;
    if top.is_empty() || size.x > 0.8 || size.y > 0.8 {
        return None;
    }
    // The surface: the cells within 3 cm of the most common height (2 cm bins).
    let bin = |z: f64| (z / 0.02).round() as i64;
    let mut counts = std::collections::BTreeMap::<i64, usize>::new();
    for &(_, z) in &top {
        *counts.entry(bin(z)).or_default() += 1;
    }
    let (&common, _) = counts.iter().max_by_key(|(b, n)| (**n, -**b))?;
    let mut cells: Vec<usize> = top
        .iter()
        .filter(|(_, z)| (bin(*z) - common).abs() <= 1)
        .map(|&(k, _)| k)
        .collect();
    cells.sort_unstable();
    cells.dedup();
    let top_z = top
        .iter()
        .filter(|(_, z)| (bin(*z) - common).abs() <= 1)
        .map(|&(_, z)| z)
        .fold(f64::NEG_INFINITY, f64::max);
    let centre = cells
        .iter()
        .map(|&k| map.centre(k % map.nx, k / map.nx))
        .sum::<DVec2>()
        / cells.len() as f64;
    // The backrest: its own geometry 15 cm and more over the seat, weighted by area; none of
    // it over the middle of the seat (a shelf, a cabinet's board).
    let (mut back, mut weight) = (DVec2::ZERO, 0.0);
    let centre_lo = centre - settings.min_half_width_m;
    let centre_hi = centre + settings.min_half_width_m;
    for v in &tris {
        let part = clip_z(v, top_z + 0.15, true);
        if part.len() < 3 {
            continue;
        }
        let over = clip_z(&part, top_z + settings.headroom_m, false);
        let xy: Vec<DVec2> = over.iter().map(|p| DVec2::new(p.x, p.y)).collect();
        if xy.len() >= 3 && convex_overlaps_rect(&xy, centre_lo, centre_hi, 0.0, false) {
            return None;
        }
        let area = (part[1] - part[0])
            .cross(part[2] - part[0])
            .length()
            .max(1e-9);
        let c = part.iter().map(|p| DVec2::new(p.x, p.y)).sum::<DVec2>() / part.len() as f64;
        back += c * area;
        weight += area;
    }
    if weight <= 0.0 || (centre - back / weight).length() < 0.05 {
        return None;
    }
    let facing = (centre - back / weight).try_normalize()?;
    let footprint = occupancy(map, tris.iter(), None);
    let inside = |k: usize| footprint.binary_search(&k).is_ok();
    let inner: Vec<usize> = footprint
        .iter()
        .copied()
        .filter(|&k| {
            let (i, j) = (k % map.nx, k / map.nx);
            i > 0
                && j > 0
                && i + 1 < map.nx
                && j + 1 < map.ny
                && [k - 1, k + 1, k - map.nx, k + map.nx]
                    .into_iter()
                    .all(inside)
        })
        .collect();
    Some(ChairShape {
        top_z,
        cells,
        centre,
        facing,
        footprint,
        inner,
        lo,
        hi,
    })
}

/// Cells overlapped by the given triangles between step and head height over the floor
/// (`band`: between those world heights instead), in ascending order.
fn occupancy<'a>(
    map: &WalkableMap,
    tris: impl Iterator<Item = &'a [Vec3; 3]>,
    band: Option<(f64, f64)>,
) -> Vec<usize> {
    let (lo_z, hi_z) = band.unwrap_or((
        map.floor_z_m + map.settings.stepped_over_m(),
        map.floor_z_m + map.settings.head_height_m,
    ));
    let mut cells = Vec::new();
    for v in tris {
        let part = clip_z(&clip_z(v, lo_z, true), hi_z, false);
        if part.is_empty() {
            continue;
        }
        let p: Vec<DVec2> = part.iter().map(|q| DVec2::new(q.x, q.y)).collect();
        let lo = p.iter().fold(DVec2::splat(f64::INFINITY), |a, b| a.min(*b));
        let hi = p
            .iter()
            .fold(DVec2::splat(f64::NEG_INFINITY), |a, b| a.max(*b));
        let (ri, rj) = map.cell_range(lo, hi);
        for j in rj {
            for i in ri.clone() {
                let c_lo = map.origin + DVec2::new(i as f64, j as f64) * map.cell_m;
                if convex_overlaps_rect(&p, c_lo, c_lo + DVec2::splat(map.cell_m), 0.0, true) {
                    cells.push(j * map.nx + i);
                }
            }
        }
    }
    cells.sort_unstable();
    cells.dedup();
    cells
}

/// Per cell, whether the triangles `tris` overlap it between step and head height over the
/// floor (`band`: between those world heights).
fn occupied(map: &WalkableMap, tris: &[[Vec3; 3]], band: Option<(f64, f64)>) -> Vec<bool> {
    let mut out = vec![false; map.nx * map.ny];
    for k in occupancy(map, tris.iter(), band) {
        out[k] = true;
    }
    out
}

/// How far `chair` is pulled back (the first pull of 5 cm steps from `min_m` to 1 m that
/// works) and where the walk to it ends: the chair slid there over floor with nothing up to
/// its seat's height in the way (`low`), the pulled chair on floor free of everything else
/// (`others`), nothing over its seat within the headroom (`covers`), free floor where the
/// person stands in front of it to sit down, and walkable floor within [`MAX_STEP_IN_M`] of that from which a straight step in
/// crosses free floor only.
#[allow(clippy::too_many_arguments)]
fn pull_out(
    map: &WalkableMap,
    settings: &ChairNeeds,
    chair: &ChairShape,
    others: &[bool],
    low: &[bool],
    covers: &[bool],
    min_m: f64,
) -> Option<(DVec2, Pull)> {
    let free = |p: DVec2| {
        map.cell_of(p).is_some_and(|(i, j)| {
            let k = j * map.nx + i;
            map.has_floor[k] && !others[k]
        })
    };
    let disk = |c: DVec2, r: f64| {
        let n = (r / map.cell_m).ceil() as i64;
        (-n..=n)
            .flat_map(move |a| (-n..=n).map(move |b| DVec2::new(a as f64, b as f64)))
            .map(move |d| c + d * map.cell_m)
            .filter(move |p| p.distance(c) <= r)
    };
    for step in 1..=20 {
        let d = 0.05 * step as f64;
        if d > MAX_PULL_M + 1e-9 {
            break;
        }
        let offset = -chair.facing * d;
        let moved_cells = |cells: &[usize]| -> Vec<DVec2> {
            cells
                .iter()
                .map(|&k| map.centre(k % map.nx, k / map.nx) + offset)
                .collect()
        };
        let (moved, inner) = (moved_cells(&chair.footprint), moved_cells(&chair.inner));
        // Slid along the floor: nothing up to the seat's height in the way, at any pull.
        let slides = inner.iter().all(|&p| {
            map.cell_of(p)
                .is_some_and(|(i, j)| map.has_floor[j * map.nx + i] && !low[j * map.nx + i])
        });
        if !slides {
            break;
        }
        if d < min_m - 1e-9 {
            continue;
        }
        let stands_on_free_floor = inner.iter().all(|&p| free(p));
        // Not where the pulled chair stands (with a body's half width round it).
        let clear_of_chair = |p: DVec2, r: f64| moved.iter().all(|q| q.distance(p) > r);
        let pelvis = chair.centre + offset;
        let room_above = disk(pelvis, settings.min_half_width_m)
            .all(|p| map.cell_of(p).is_some_and(|(i, j)| !covers[j * map.nx + i]));
        let feet = pelvis + chair.facing * STAND_IN_FRONT_M;
        // (The legs touch the chair's front edge as the person sits down.)
        let room_in_front = disk(feet, FEET_CLEARANCE_M).all(&free) && clear_of_chair(feet, 0.05);
        if !(stands_on_free_floor && room_above && room_in_front) {
            continue;
        }
        // Where the walk ends: the nearest walkable cell with room round it whose straight
        // step to the feet crosses free floor only.
        let reach = (MAX_STEP_IN_M / map.cell_m).ceil() as i64;
        let (fi, fj) = map.cell_of(feet)?;
        let mut best: Option<(f64, DVec2)> = None;
        for b in -reach..=reach {
            for a in -reach..=reach {
                let (i, j) = (fi as i64 + a, fj as i64 + b);
                if i < 0 || j < 0 || i >= map.nx as i64 || j >= map.ny as i64 {
                    continue;
                }
                let k = j as usize * map.nx + i as usize;
                let c = map.centre(i as usize, j as usize);
                let dist = c.distance(feet);
                if !map.walkable[k]
                    || map.sdf_m[k] < settings.stand_clearance_m
                    || dist > MAX_STEP_IN_M
                    || best.is_some_and(|(bd, _)| bd <= dist)
                {
                    continue;
                }
                let steps = (dist / (0.5 * map.cell_m)).ceil().max(1.0) as usize;
                let step_in = (0..=steps).map(|s| c.lerp(feet, s as f64 / steps as f64));
                if clear_of_chair(c, 0.25)
                    && step_in.clone().all(|p| free(p) && clear_of_chair(p, 0.1))
                {
                    best = Some((dist, c));
                }
            }
        }
        let (_, stand) = best?;
        // Floor the person may stand on while stepping in and sitting down: free of everything
        // but the chair, round the feet and along the step.
        let mut free_cells: Vec<usize> = disk(feet, 0.6)
            .chain(disk(stand.lerp(feet, 0.5), 0.5))
            .filter(|&p| free(p) && clear_of_chair(p, 0.0))
            .filter_map(|p| map.cell_of(p).map(|(i, j)| j * map.nx + i))
            .collect();
        free_cells.sort_unstable();
        free_cells.dedup();
        return Some((
            stand,
            Pull {
                offset_m: offset.to_array(),
                free_cells,
            },
        ));
    }
    None
}

/// How far the seat (`cells`) reaches in front of `pelvis` along `facing` (m).
fn front_depth(map: &WalkableMap, cells: &[usize], pelvis: DVec2, facing: DVec2) -> f64 {
    let on = |p: DVec2| {
        map.cell_of(p)
            .is_some_and(|(i, j)| cells.binary_search(&(j * map.nx + i)).is_ok())
    };
    let mut s = 0.0;
    while s < 1.0 && on(pelvis + facing * s) {
        s += 0.5 * map.cell_m;
    }
    s
}
