//! Exact Euclidean distance transform on a grid (Felzenszwalb & Huttenlocher, 2012) and the
//! signed distance field built from it.

/// Squared distance (in cells²) from every cell centre to the nearest `target` cell centre;
/// `f64::INFINITY` where there is no target at all.
pub(crate) fn squared_edt(target: &[bool], nx: usize, ny: usize) -> Vec<f64> {
    let mut d: Vec<f64> = target
        .iter()
        .map(|&t| if t { 0.0 } else { f64::INFINITY })
        .collect();
    let mut f = vec![0.0; nx.max(ny)];
    let mut out = vec![0.0; nx.max(ny)];
    // Columns (along y), then rows (along x).
    for i in 0..nx {
        for j in 0..ny {
            f[j] = d[j * nx + i];
        }
        edt_1d(&f[..ny], &mut out[..ny]);
        for j in 0..ny {
            d[j * nx + i] = out[j];
        }
    }
    for j in 0..ny {
        f[..nx].copy_from_slice(&d[j * nx..(j + 1) * nx]);
        edt_1d(&f[..nx], &mut out[..nx]);
        d[j * nx..(j + 1) * nx].copy_from_slice(&out[..nx]);
    }
    d
}

/// 1D squared distance transform of sampled function `f` (lower envelope of parabolas).
fn edt_1d(f: &[f64], out: &mut [f64]) {
    let n = f.len();
    let mut v = vec![0usize; n];
    let mut z = vec![0.0f64; n + 1];
    let mut k = 0usize;
    let first = match (0..n).find(|&q| f[q].is_finite()) {
        Some(q) => q,
        None => {
            out.fill(f64::INFINITY);
            return;
        }
    };
    v[0] = first;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in first + 1..n {
        if !f[q].is_finite() {
            continue;
        }
        loop {
            let p = v[k];
            let s =
                ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
            if s <= z[k] && k > 0 {
                k -= 1;
                continue;
            }
            if s <= z[k] {
                // k == 0 and the new parabola dominates everywhere.
                v[0] = q;
                z[1] = f64::INFINITY;
                break;
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f64::INFINITY;
            break;
        }
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dq = q as f64 - p as f64;
        *o = dq * dq + f[p];
    }
}

/// Signed distance (m) per cell: positive inside `inside` cells (distance from the cell centre
/// to the nearest outside cell centre minus half a cell, i.e. to the shared cell boundary along
/// the axes), negative outside, by the same rule.
pub(crate) fn signed_distance(inside: &[bool], nx: usize, ny: usize, cell_m: f64) -> Vec<f64> {
    let outside: Vec<bool> = inside.iter().map(|&b| !b).collect();
    let to_outside = squared_edt(&outside, nx, ny);
    let to_inside = squared_edt(inside, nx, ny);
    inside
        .iter()
        .enumerate()
        .map(|(k, &ins)| {
            if ins {
                (to_outside[k].sqrt() - 0.5) * cell_m
            } else {
                -(to_inside[k].sqrt() - 0.5) * cell_m
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edt_matches_brute_force() {
        let (nx, ny) = (23, 17);
        let target: Vec<bool> = (0..nx * ny).map(|k| (k * 7919 + 13) % 41 == 0).collect();
        let d = squared_edt(&target, nx, ny);
        for j in 0..ny {
            for i in 0..nx {
                let mut best = f64::INFINITY;
                for jj in 0..ny {
                    for ii in 0..nx {
                        if target[jj * nx + ii] {
                            let (dx, dy) = (i as f64 - ii as f64, j as f64 - jj as f64);
                            best = best.min(dx * dx + dy * dy);
                        }
                    }
                }
                assert_eq!(d[j * nx + i], best, "cell {i},{j}");
            }
        }
    }
}
