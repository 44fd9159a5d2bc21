//! The partition stage: bodies to nodes (explicit lists or 2×2 grid quadrants), link
//! ownership (internal links, the thesis ring, the general rule, the file's overrides).
//!
//! Nodes are 0-based here and 1-based in the file and in every message (`node 3` is
//! `partition.nodes[2]`), as traces name them.

use std::collections::BTreeMap;

use crate::kernel::SimTime;

use super::bodies::Ids;
use crate::error::{num, Error, Result};
use crate::scenario::file::{
    CouplingFile, CouplingName, CouplingSpecFile, GhostsFile, GridFile, LinkOwnerFile,
    PartitionFile,
};
use crate::scenario::model::{BodySpec, Coupling, GhostMode, Lines, LinkSpec, PartitionSpec, Tank};

/// Validates `partition` against the model (`grid` is the model's grid section, if it
/// is one; `bodies` and `links` are the validated model in file order; `joints`:
/// whether the model has joints, which chooses the default tank).
pub(super) fn partition(
    p: &PartitionFile,
    grid: Option<&GridFile>,
    ids: &Ids,
    (bodies, links): (&[BodySpec], &[LinkSpec]),
    joints: bool,
) -> Result<PartitionSpec> {
    let (nodes, node_of, ring) = match (&p.nodes, p.quadrants) {
        (Some(lists), false) => {
            let node_of = explicit(lists, ids, bodies)?;
            (lists.len(), node_of, false)
        }
        (None, true) => quadrants(grid)?,
        (Some(_), true) => {
            return Err(Error::invalid(
                "partition",
                "give either `nodes` or `\"quadrants\": true`, not both",
            ))
        }
        (None, false) => {
            return Err(Error::invalid(
                "partition",
                "needs either `nodes` or `\"quadrants\": true`",
            ))
        }
    };
    let constraints = constraint_counts(bodies.len(), links);
    let mut link_owner: Vec<usize> = links
        .iter()
        .map(|l| {
            let (na, nb) = (node_of[l.a], node_of[l.b]);
            if na != nb && !ring {
                // Outside the thesis ring: a border link's far body (the one that is
                // not its owner's) is both the owner's ghost and the body that feels the
                // link's force as a sample extrapolated over its age. The owner is the
                // side whose body is driven hardest by forces only its own node
                // computes: its other constraints per kilogram. Then the far body is the
                // better-predicted ghost, and an error in the force it receives makes
                // the smaller acceleration (method §3 has the scenes that decided it).
                let drive = |b: usize| (constraints[b] - 1) as f64 / bodies[b].mass;
                let (da, db) = (drive(l.a), drive(l.b));
                if da != db {
                    return if da > db { na } else { nb };
                }
            }
            // A tie: the general rule names the lower-numbered body (by id, not by
            // position in the file: `bodies` may list ids in any order).
            let lower = if bodies[l.a].id <= bodies[l.b].id {
                l.a
            } else {
                l.b
            };
            default_owner(na, nb, node_of[lower], ring)
        })
        .collect();
    overrides(&p.link_owners, &node_of, bodies, links, &mut link_owner)?;
    Ok(PartitionSpec {
        nodes,
        node_of,
        link_owner,
        ghosts: match p.ghosts {
            GhostsFile::Integrate => GhostMode::Integrate,
            GhostsFile::Hold => GhostMode::Hold,
        },
        coupling: coupling(&p.coupling, joints)?,
    })
}

/// The default tank of the `passive` coupling on a scene of distance links, per border
/// port [J]: chosen on the thesis net (docs/method.md §3.1 gives the measurements).
pub const DEFAULT_TANK: f64 = 40.0;
/// The default tank of the `passive` coupling on a scene with joints: each node's share
/// of its energy scale, the largest kinetic energy its own bodies have held plus the
/// work the scene's forces put into them (docs/method.md §3.1 gives the measurements).
pub const DEFAULT_TANK_SHARE: f64 = 0.1;
/// The largest `tank_share` accepted.
pub const MAX_TANK_SHARE: f64 = 10.0;

/// The default extrapolation horizon of `predict` and `passive` [s]: chosen on the
/// thesis scene (docs/guide.md "Coupling across partitions" gives the measurements).
pub const DEFAULT_EXTRAPOLATE: f64 = 0.01;

/// The age above which the `passive` scheme turns a border link into a transmission
/// line [s] (docs/guide.md "Coupling across partitions" gives the measurements).
pub const DEFAULT_LINES_ABOVE: f64 = 0.04;

/// `partition.coupling`; `joints`: whether the model has joints (the default tank).
///
/// *Why the default tank depends on the model*: on the thesis net the predictor's
/// energy errors swing by far more than the net's own kinetic energy between reports
/// and balance out over time; a tank sized from that energy (any share up to 1) brakes
/// the swings and drains the net (method §3.1 measures it), while 40 J per port keeps
/// it within its band. On a mechanism of joints the same 40 J exceeds what the whole
/// mechanism holds (a double pendulum of 22 J took 34 J from the ports at 20 ms), so
/// there the tank is a share of the mechanism's own energy.
fn coupling(c: &CouplingFile, joints: bool) -> Result<Coupling> {
    let spec = match *c {
        CouplingFile::Name(scheme) => CouplingSpecFile {
            scheme,
            tank: None,
            tank_share: None,
            extrapolate: None,
            impedance: None,
            lines_above: None,
        },
        CouplingFile::Spec(spec) => spec,
    };
    let name = spec.scheme;
    let not_for = |field: &str, value: Option<f64>, schemes: &[CouplingName], why: &str| {
        if value.is_some() && !schemes.contains(&name) {
            Err(Error::invalid(format!("partition.coupling.{field}"), why))
        } else {
            Ok(())
        }
    };
    use CouplingName::{Passive, Predict, Tlm};
    not_for(
        "extrapolate",
        spec.extrapolate,
        &[Predict, Passive, Tlm],
        "the \"reset\" scheme holds forces and does not extrapolate",
    )?;
    not_for(
        "tank",
        spec.tank,
        &[Passive],
        "only the \"passive\" scheme has a tank",
    )?;
    not_for(
        "tank_share",
        spec.tank_share,
        &[Passive],
        "only the \"passive\" scheme has a tank",
    )?;
    not_for(
        "impedance",
        spec.impedance,
        &[Passive, Tlm],
        "only the \"passive\" and \"tlm\" schemes have transmission lines",
    )?;
    not_for(
        "lines_above",
        spec.lines_above,
        &[Passive],
        "only the \"passive\" scheme chooses its lines by age (\"tlm\" makes every border link a line)",
    )?;
    // A time in [0, max] s.
    let time = |field: &str, secs: f64, max: f64| match SimTime::from_secs_f64(secs) {
        Some(t) if (0.0..=max).contains(&secs) => Ok(t),
        _ => Err(Error::invalid(
            format!("partition.coupling.{field}"),
            format!("must be a time between 0 and {max} s, got {}", num(secs)),
        )),
    };
    let extrapolate = time(
        "extrapolate",
        spec.extrapolate.unwrap_or(DEFAULT_EXTRAPOLATE),
        10.0,
    )?;
    let impedance = spec.impedance;
    if let Some(z) = impedance.filter(|z| !(z.is_finite() && *z > 0.0)) {
        return Err(Error::invalid(
            "partition.coupling.impedance",
            format!("must be a finite impedance > 0 N·s/m, got {}", num(z)),
        ));
    }
    let above = time(
        "lines_above",
        spec.lines_above.unwrap_or(DEFAULT_LINES_ABOVE),
        1000.0,
    )?;
    match name {
        CouplingName::Reset => Ok(Coupling::Reset),
        Predict => Ok(Coupling::Predict { extrapolate }),
        Passive => {
            let tank = match (spec.tank, spec.tank_share) {
                (Some(_), Some(_)) => {
                    return Err(Error::invalid(
                        "partition.coupling.tank_share",
                        "give either a fixed \"tank\" [J] or a \"tank_share\", not both",
                    ))
                }
                (Some(tank), None) => {
                    if !(tank.is_finite() && tank >= 0.0) {
                        return Err(Error::invalid(
                            "partition.coupling.tank",
                            format!("must be a finite energy ≥ 0 J, got {}", num(tank)),
                        ));
                    }
                    Tank::Fixed(tank)
                }
                (None, None) if !joints => Tank::Fixed(DEFAULT_TANK),
                (None, share) => {
                    let share = share.unwrap_or(DEFAULT_TANK_SHARE);
                    if !(0.0..=MAX_TANK_SHARE).contains(&share) {
                        return Err(Error::invalid(
                            "partition.coupling.tank_share",
                            format!(
                                "must be a share between 0 and {MAX_TANK_SHARE}, got {}",
                                num(share)
                            ),
                        ));
                    }
                    Tank::Share(share)
                }
            };
            Ok(Coupling::Passive {
                tank,
                extrapolate,
                lines: Lines { above, impedance },
            })
        }
        Tlm => Ok(Coupling::Tlm {
            extrapolate,
            lines: Lines {
                above: SimTime::ZERO,
                impedance,
            },
        }),
    }
}

/// `partition.nodes`: every body in exactly one node, no node empty.
fn explicit(lists: &[Vec<u32>], ids: &Ids, bodies: &[BodySpec]) -> Result<Vec<usize>> {
    if lists.is_empty() {
        return Err(Error::invalid(
            "partition.nodes",
            "must list at least one node (got [])",
        ));
    }
    let mut node_of: Vec<Option<usize>> = vec![None; bodies.len()];
    for (n, list) in lists.iter().enumerate() {
        if list.is_empty() {
            return Err(Error::invalid(
                format!("partition.nodes[{n}]"),
                format!("node {} is empty (got [])", n + 1),
            ));
        }
        for (j, &id) in list.iter().enumerate() {
            let path = format!("partition.nodes[{n}][{j}]");
            let body = ids.index(&path, id)?;
            if let Some(first) = node_of[body] {
                return Err(Error::invalid(
                    path,
                    format!("body {id} is already in node {}", first + 1),
                ));
            }
            node_of[body] = Some(n);
        }
    }
    let missing: Vec<u32> = bodies
        .iter()
        .zip(&node_of)
        .filter(|(_, n)| n.is_none())
        .map(|(b, _)| b.id)
        .collect();
    if let Some(&first) = missing.first() {
        let more = match missing.len() {
            1 => String::new(),
            n => format!(" (nor are {} more bodies)", n - 1),
        };
        return Err(Error::invalid(
            "partition.nodes",
            format!("body {first} is in no node{more}"),
        ));
    }
    Ok(node_of.into_iter().flatten().collect())
}

/// `"quadrants": true`: 2×2 blocks of a grid with even rows and cols. Returns the node
/// count, the node of each body and whether the blocks form the thesis ring.
///
/// The 2×2 block grid (a 4×4 body grid) is numbered as the thesis ring 1–2–3–4–1 going
/// round the grid (1 at the origin corner, 2 along +x, 3 opposite 1, 4 along +y from
/// 1); any other block grid row by row from the origin corner.
fn quadrants(grid: Option<&GridFile>) -> Result<(usize, Vec<usize>, bool)> {
    let path = "partition.quadrants";
    let Some(g) = grid else {
        return Err(Error::invalid(
            path,
            "needs a `grid` model (got explicit `bodies`); list the nodes instead",
        ));
    };
    if g.rows % 2 != 0 || g.cols % 2 != 0 {
        return Err(Error::invalid(
            path,
            format!(
                "needs a grid with an even number of rows and cols (got a {}×{} grid)",
                g.rows, g.cols
            ),
        ));
    }
    // rows·cols ≤ MAX_GRID_BODIES, checked by the model stage, so these fit a usize.
    let (rows, cols) = (g.rows as usize, g.cols as usize);
    let (block_rows, block_cols) = (rows / 2, cols / 2);
    let ring = block_rows == 2 && block_cols == 2;
    // Thesis ring by (block row, block col): (0,0)→1, (0,1)→2, (1,1)→3, (1,0)→4.
    let ring_node = [[0, 1], [3, 2]];
    let node_of = (0..rows * cols)
        .map(|i| {
            let (br, bc) = (i / cols / 2, i % cols / 2);
            if ring {
                ring_node[br][bc]
            } else {
                br * block_cols + bc
            }
        })
        .collect();
    Ok((block_rows * block_cols, node_of, ring))
}

/// The owner of a link between nodes `a` and `b` without an override: the common node
/// of an internal link; on the thesis ring the node whose clockwise neighbour is the
/// other (1 owns 1–2, 2 owns 2–3, 3 owns 3–4, 4 owns 4–1); else `lower`, the node of
/// the link's lower-numbered body (method §3).
fn default_owner(a: usize, b: usize, lower: usize, ring: bool) -> usize {
    if a == b || (ring && (a + 1) % 4 == b) {
        a
    } else if ring && (b + 1) % 4 == a {
        b
    } else {
        lower
    }
}

/// How many constraints act on each body: every distance link and every joint once
/// (a joint's rows are one constraint), world anchors included.
fn constraint_counts(bodies: usize, links: &[LinkSpec]) -> Vec<usize> {
    let mut count = vec![0; bodies];
    for l in links {
        // Only a joint's first row counts it.
        if l.joint.is_some_and(|(_, row)| row > 0) {
            continue;
        }
        count[l.a] += 1;
        if !l.world && l.b != l.a {
            count[l.b] += 1;
        }
    }
    count
}

/// Applies `partition.link_owners`: border links only, to one of their two nodes, each
/// link at most once.
fn overrides(
    entries: &[LinkOwnerFile],
    node_of: &[usize],
    bodies: &[BodySpec],
    links: &[LinkSpec],
    link_owner: &mut [usize],
) -> Result<()> {
    let mut seen = BTreeMap::new();
    for (i, o) in entries.iter().enumerate() {
        let path = format!("partition.link_owners[{i}]");
        let k = o.link;
        if k == 0 || k > links.len() {
            let range = match links.len() {
                0 => "the model has no links".to_string(),
                n => format!("links are numbered 1 to {n}"),
            };
            return Err(Error::invalid(
                format!("{path}.link"),
                format!("no link {k} ({range})"),
            ));
        }
        if let Some(first) = seen.insert(k, i) {
            return Err(Error::invalid(
                format!("{path}.link"),
                format!("link {k} is given an owner twice (also partition.link_owners[{first}])"),
            ));
        }
        let l = &links[k - 1];
        if let Some((j, _)) = l.joint {
            // A joint's rows travel as one message from one owner.
            return Err(Error::invalid(
                format!("{path}.link"),
                format!(
                    "{k} is a row of joint J{} (links are numbered 1 to {}); a joint is \
                     owned by the general rule",
                    j + 1,
                    links.iter().filter(|l| l.joint.is_none()).count()
                ),
            ));
        }
        let (a, b) = (node_of[l.a], node_of[l.b]);
        let ends = format!("bodies {}–{}", bodies[l.a].id, bodies[l.b].id);
        if a == b {
            return Err(Error::invalid(
                format!("{path}.link"),
                format!(
                    "link {k} ({ends}) lies inside node {}; only a border link takes an owner",
                    a + 1
                ),
            ));
        }
        if o.node != a + 1 && o.node != b + 1 {
            return Err(Error::invalid(
                format!("{path}.node"),
                format!(
                    "must be node {} or node {}, the nodes of link {k} ({ends}) (got {})",
                    a.min(b) + 1,
                    a.max(b) + 1,
                    o.node
                ),
            ));
        }
        link_owner[k - 1] = o.node - 1;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
