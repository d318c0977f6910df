//! Rays through the walkable map by a DDA over grid cells (Amanatides & Woo), exact to the
//! cell boundaries: the hit distance is where the ray enters the first blocked cell.
//! Blocked cells are closed squares: a ray that grazes a blocked cell's edge or corner hits it.

use super::Ray2;
use crate::scene::WalkableMap;

/// Distance to the first blocked cell along `ray`, or `None` within `max_t`.
pub(crate) fn hit_grid(map: &WalkableMap, ray: Ray2, max_t: f64) -> Option<f64> {
    let cell = map.cell_m;
    let q = (ray.origin - map.origin) / cell;
    let mut i = q.x.floor() as i64;
    let mut j = q.y.floor() as i64;
    // A start exactly on a cell boundary touches the cells on both sides.
    let on_x_edge = q.x == q.x.floor();
    let on_y_edge = q.y == q.y.floor();
    if map.blocked(i, j)
        || (on_x_edge && map.blocked(i - 1, j))
        || (on_y_edge && map.blocked(i, j - 1))
        || (on_x_edge && on_y_edge && map.blocked(i - 1, j - 1))
    {
        return Some(0.0);
    }
    let (dx, dy) = (ray.dir.x, ray.dir.y);
    let step_i: i64 = if dx > 0.0 { 1 } else { -1 };
    let step_j: i64 = if dy > 0.0 { 1 } else { -1 };
    // For a ray exactly along a grid line, the cells on the other side of the line are touched.
    let side_j = (dy == 0.0 && on_y_edge).then_some(j - 1);
    let side_i = (dx == 0.0 && on_x_edge).then_some(i - 1);
    let t_delta_x = if dx != 0.0 {
        cell / dx.abs()
    } else {
        f64::INFINITY
    };
    let t_delta_y = if dy != 0.0 {
        cell / dy.abs()
    } else {
        f64::INFINITY
    };
    let next_x = |i: i64| map.origin.x + (i + if dx > 0.0 { 1 } else { 0 }) as f64 * cell;
    let next_y = |j: i64| map.origin.y + (j + if dy > 0.0 { 1 } else { 0 }) as f64 * cell;
    let mut t_max_x = if dx != 0.0 {
        (next_x(i) - ray.origin.x) / dx
    } else {
        f64::INFINITY
    };
    let mut t_max_y = if dy != 0.0 {
        (next_y(j) - ray.origin.y) / dy
    } else {
        f64::INFINITY
    };
    // On a boundary moving backwards, the first crossing is one cell further.
    if dx < 0.0 && on_x_edge {
        t_max_x = 0.0;
    }
    if dy < 0.0 && on_y_edge {
        t_max_y = 0.0;
    }
    loop {
        let t = t_max_x.min(t_max_y);
        if t > max_t {
            return None;
        }
        let tie = (t_max_x - t_max_y).abs() <= 1e-12 * (1.0 + t);
        if tie {
            // Through a corner: the two side cells and the diagonal one are all touched.
            if map.blocked(i + step_i, j)
                || map.blocked(i, j + step_j)
                || map.blocked(i + step_i, j + step_j)
            {
                return Some(t);
            }
            i += step_i;
            j += step_j;
            t_max_x += t_delta_x;
            t_max_y += t_delta_y;
        } else if t_max_x < t_max_y {
            i += step_i;
            t_max_x += t_delta_x;
            if map.blocked(i, j) || side_j.is_some_and(|_| map.blocked(i, j - 1)) {
                return Some(t);
            }
        } else {
            j += step_j;
            t_max_y += t_delta_y;
            if map.blocked(i, j) || side_i.is_some_and(|_| map.blocked(i - 1, j)) {
                return Some(t);
            }
        }
    }
}
