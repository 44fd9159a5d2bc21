//! The `grid R×C` generator (method §3).
//!
//! A grid is expanded into the same explicit [`BodyFile`]/[`LinkFile`] entries a user
//! could have written, so both kinds of model go through one validation path:
//!
//! ```text
//!   y
//!   ▲   13 ─ 14 ─ 15 ─ 16        ids 1..R·C row by row from the corner at the origin;
//!   │    │    │    │    │        body (r, c) at (c·L, r·L, 0), r = 0..R, c = 0..C;
//!   │    9 ─ 10 ─ 11 ─ 12        links between 4-neighbours, numbered row by row,
//!   │    │    │    │    │        each body's +x link before its +y link:
//!   │    5 ─  6 ─  7 ─  8        L1 = 1–2, L2 = 1–5, L3 = 2–3, L4 = 2–6, …
//!   │    │    │    │    │        anchors at the centres, length = spacing L.
//!   │    1 ─  2 ─  3 ─  4
//!   └──────────────────────▶ x
//! ```

use super::file::{BodyFile, GridFile, LinkFile};
use super::validate::checks::{num, positive};
use crate::error::{Error, Result};

/// Largest number of bodies a grid may generate: a guard against a typo (`"rows": 40000`)
/// exhausting memory before the run even starts. 10⁶ bodies is a 1000×1000 grid, far
/// beyond what a lock-step run of this simulator can integrate in useful time.
pub const MAX_GRID_BODIES: u64 = 1_000_000;

/// Checks a grid section and expands it into explicit bodies and links.
///
/// `path` names the section in error messages (`model.grid`). Rows and columns must be
/// ≥ 1 with at most [`MAX_GRID_BODIES`] bodies; spacing, mass and size must be finite
/// and > 0, and extreme enough values to give infinite coordinates or a zero inertia are
/// rejected too, so the generated bodies and links always pass validation. Bodies start at rest with the identity orientation and the cube inertia;
/// every link has its anchors at the centres and `length = spacing` (written out rather
/// than defaulted, so round-off in `c·spacing` cannot leave the grid off its manifold).
pub fn expand(grid: &GridFile, path: &str) -> Result<(Vec<BodyFile>, Vec<LinkFile>)> {
    for (key, n) in [("rows", grid.rows), ("cols", grid.cols)] {
        if n == 0 {
            return Err(Error::invalid(
                format!("{path}.{key}"),
                "must be ≥ 1 (got 0)",
            ));
        }
    }
    let count = u64::from(grid.rows) * u64::from(grid.cols);
    if count > MAX_GRID_BODIES {
        return Err(Error::invalid(
            format!("{path}.rows"),
            format!(
                "a {}×{} grid has {count} bodies, more than the limit {MAX_GRID_BODIES}",
                grid.rows, grid.cols
            ),
        ));
    }
    let spacing = positive(&format!("{path}.spacing"), grid.spacing)?;
    let mass = positive(&format!("{path}.mass"), grid.mass)?;
    let size = positive(&format!("{path}.size"), grid.size)?;
    // Catch extreme values here, where the error can name the grid's own keys.
    let far = f64::from(grid.rows.max(grid.cols) - 1) * spacing;
    if !far.is_finite() {
        return Err(Error::invalid(
            format!("{path}.spacing"),
            format!("puts bodies at infinite coordinates (got {})", num(spacing)),
        ));
    }
    let cube = mass * size * size / 6.0;
    if !(cube.is_finite() && cube > 0.0) {
        return Err(Error::invalid(
            format!("{path}.size"),
            format!(
                "gives the cube inertia m s²/6 = {} for mass {} and size {}",
                num(cube),
                num(mass),
                num(size)
            ),
        ));
    }

    let (rows, cols) = (grid.rows, grid.cols);
    // count ≤ MAX_GRID_BODIES < u32::MAX, so every id below fits in a u32.
    let id = |r: u32, c: u32| r * cols + c + 1;
    let mut bodies = Vec::with_capacity(count as usize);
    let mut links = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            bodies.push(BodyFile {
                id: id(r, c),
                mass,
                size,
                inertia: None,
                position: [f64::from(c) * spacing, f64::from(r) * spacing, 0.0],
                velocity: [0.0; 3],
                orientation: [1.0, 0.0, 0.0, 0.0],
                angular_velocity: [0.0; 3],
            });
            let link_to = |other: u32| LinkFile {
                a: id(r, c),
                b: other,
                length: Some(spacing),
                anchor_a: [0.0; 3],
                anchor_b: [0.0; 3],
            };
            if c + 1 < cols {
                links.push(link_to(id(r, c + 1)));
            }
            if r + 1 < rows {
                links.push(link_to(id(r + 1, c)));
            }
        }
    }
    Ok((bodies, links))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: u32, cols: u32) -> GridFile {
        GridFile {
            rows,
            cols,
            spacing: 1.8,
            mass: 1.0,
            size: 0.2,
        }
    }

    fn pairs(links: &[LinkFile]) -> Vec<(u32, u32)> {
        links.iter().map(|l| (l.a, l.b)).collect()
    }

    #[test]
    fn thesis_grid_numbers_links_row_by_row_x_before_y() {
        let (bodies, links) = expand(&grid(4, 4), "model.grid").unwrap();
        assert_eq!(bodies.len(), 16);
        assert_eq!(links.len(), 24);
        assert_eq!(
            pairs(&links[..7]),
            [(1, 2), (1, 5), (2, 3), (2, 6), (3, 4), (3, 7), (4, 8)]
        );
        // The last row has only +x links.
        assert_eq!(pairs(&links[21..]), [(13, 14), (14, 15), (15, 16)]);
        let ids: Vec<u32> = bodies.iter().map(|b| b.id).collect();
        assert_eq!(ids, (1..=16).collect::<Vec<_>>());
        assert_eq!(bodies[1].position, [1.8, 0.0, 0.0]);
        assert_eq!(bodies[4].position, [0.0, 1.8, 0.0]);
        assert!(links.iter().all(|l| l.length == Some(1.8)));
    }

    #[test]
    fn link_count_is_that_of_a_grid_graph() {
        for (r, c) in [(1, 1), (1, 5), (5, 1), (2, 3), (3, 7)] {
            let (bodies, links) = expand(&grid(r, c), "g").unwrap();
            assert_eq!(bodies.len() as u32, r * c, "{r}×{c} bodies");
            assert_eq!(
                links.len() as u32,
                r * (c - 1) + c * (r - 1),
                "{r}×{c} links"
            );
        }
    }

    #[test]
    fn rejects_empty_oversized_and_non_positive_grids() {
        let err = |g: GridFile| expand(&g, "model.grid").unwrap_err().to_string();
        assert!(err(grid(0, 4)).starts_with("model.grid.rows: must be ≥ 1"));
        assert!(err(grid(4, 0)).starts_with("model.grid.cols: must be ≥ 1"));
        assert!(err(grid(100_000, 100_000)).contains("more than the limit"));
        let mut g = grid(2, 2);
        g.spacing = -1.0;
        assert_eq!(err(g), "model.grid.spacing: must be > 0 (got -1)");
        let mut g = grid(2, 2);
        g.size = 0.0;
        assert_eq!(err(g), "model.grid.size: must be > 0 (got 0)");
        let mut g = grid(3, 3);
        g.spacing = 1e308;
        assert!(err(g).starts_with("model.grid.spacing: puts bodies at infinite"));
        let mut g = grid(2, 2);
        g.size = 1e-200;
        assert!(err(g).starts_with("model.grid.size: gives the cube inertia m s²/6 = 0"));
    }
}
