//! `model.joints`: each joint expanded into the constraint rows it adds (see
//! [`RowKind`]), anchored where the file says the joint is at t = 0.

use nalgebra::{UnitQuaternion, Vector3};

use super::bodies::Ids;
use super::checks::{magnitude_vector, vec_str};
use crate::error::{Error, Result};
use crate::scenario::file::{JointFile, JointTypeFile};
use crate::scenario::model::{AlignAxes, BodySpec, JointType, LinkSpec, RowKind};

/// Most joints a scenario may declare (each adds at most 6 rows to the constraint
/// system; the links' own limit is the body count's).
pub const MAX_JOINTS: usize = 100_000;

/// The rows of every joint, in joint order, each joint's rows in the order of
/// [`JointType`]: the three offsets (x, y, z), then a hinge's two or a weld's three
/// alignments; a prismatic joint's two slides, then its three alignments.
pub(super) fn joint_rows(
    joints: &[JointFile],
    ids: &Ids,
    bodies: &[BodySpec],
) -> Result<Vec<LinkSpec>> {
    if joints.len() > MAX_JOINTS {
        return Err(Error::invalid(
            "model.joints",
            format!(
                "has {} joints; at most {MAX_JOINTS} are allowed",
                joints.len()
            ),
        ));
    }
    let mut rows = Vec::new();
    // Each pair of sides (the world as `None`) and point already joined, and by which
    // joint: a second joint there repeats the first's offset rows.
    let mut seen = std::collections::BTreeMap::new();
    for (j, file) in joints.iter().enumerate() {
        let path = format!("model.joints[{j}]");
        rows.extend(joint(&path, j, file, ids, bodies)?);
        let (lo, hi) = match file.b {
            Some(b) => (Some(file.a.min(b)), Some(file.a.max(b))),
            None => (None, Some(file.a)),
        };
        let key = (lo, hi, file.at.map(f64::to_bits));
        if let Some(first) = seen.insert(key, j) {
            let between = match file.b {
                Some(b) => format!("bodies {} and {b}", file.a),
                None => format!("body {} and the world", file.a),
            };
            return Err(Error::invalid(
                path,
                format!(
                    "joins {between} at {} as model.joints[{first}] does; a constraint \
                     given twice only repeats rows (remove one, or keep the joint with more \
                     rows)",
                    vec_str(&file.at)
                ),
            ));
        }
    }
    Ok(rows)
}

/// The joint type of a file entry.
pub fn joint_type(kind: JointTypeFile) -> JointType {
    match kind {
        JointTypeFile::Ball => JointType::Ball,
        JointTypeFile::Hinge => JointType::Hinge,
        JointTypeFile::Weld => JointType::Weld,
        JointTypeFile::Prismatic => JointType::Prismatic,
    }
}

fn joint(
    path: &str,
    j: usize,
    f: &JointFile,
    ids: &Ids,
    bodies: &[BodySpec],
) -> Result<Vec<LinkSpec>> {
    let a = ids.index(&format!("{path}.a"), f.a)?;
    let b = match f.b {
        Some(id) => {
            let b = ids.index(&format!("{path}.b"), id)?;
            if b == a {
                return Err(Error::invalid(
                    format!("{path}.b"),
                    format!("a joint cannot join body {id} to itself (leave `b` out to pin it to the world)"),
                ));
            }
            Some(b)
        }
        None => None,
    };
    let at = magnitude_vector(&format!("{path}.at"), f.at)?;
    let kind = joint_type(f.kind);
    let axial = matches!(kind, JointType::Hinge | JointType::Prismatic);
    let axis = match (axial, f.axis) {
        (true, None) => {
            return Err(Error::invalid(
                format!("{path}.axis"),
                if kind == JointType::Hinge {
                    "a hinge needs the world direction it turns about, e.g. [0, 0, 1]"
                } else {
                    "a prismatic joint needs the world direction it slides along, e.g. [1, 0, 0]"
                },
            ))
        }
        (true, Some(axis)) => {
            let v = magnitude_vector(&format!("{path}.axis"), axis)?;
            let n = v.norm();
            if !(n > 0.0 && n.is_finite()) {
                return Err(Error::invalid(
                    format!("{path}.axis"),
                    format!("must not be zero (got {})", vec_str(&axis)),
                ));
            }
            Some(v / n)
        }
        (false, Some(_)) => {
            return Err(Error::invalid(
                format!("{path}.axis"),
                "only a hinge or a prismatic joint has an axis (a ball turns freely, a weld \
                 not at all)",
            ))
        }
        (false, None) => None,
    };
    // Each side's anchor: the joint point in its frame (the world point itself).
    let frame = |i: usize| -> (Vector3<f64>, UnitQuaternion<f64>) {
        (bodies[i].position, bodies[i].orientation)
    };
    let (pa, ra) = frame(a);
    let anchor_a = ra.inverse() * (at - pa);
    let (anchor_b, rb) = match b {
        Some(b) => {
            let (pb, rb) = frame(b);
            (rb.inverse() * (at - pb), Some(rb))
        }
        None => (at, None),
    };
    // A world vector in `b`'s frame (the world's own on a world row).
    let in_b = |v: Vector3<f64>| rb.map_or(v, |r| r.inverse() * v);
    let row = |r: usize, kind: RowKind| LinkSpec {
        a,
        b: b.unwrap_or(a),
        length: 0.0,
        anchor_a,
        anchor_b,
        kind,
        world: b.is_none(),
        joint: Some((j as u32, r as u32)),
    };
    // A prismatic joint's first two rows hold `a`'s anchor on the axis through `b`'s
    // (normal offsets in `b`'s frame); every other joint's first three make the
    // anchors coincide.
    let mut rows: Vec<LinkSpec> = match (kind, axis) {
        (JointType::Prismatic, Some(axis)) => {
            let (p1, p2) = normals(&axis);
            [p1, p2]
                .into_iter()
                .enumerate()
                .map(|(k, n)| row(k, RowKind::Slide(Box::new(in_b(n)))))
                .collect()
        }
        _ => (0..3u8)
            .map(|k| row(usize::from(k), RowKind::Offset(k)))
            .collect(),
    };
    let first = rows.len();
    let e = [Vector3::x(), Vector3::y(), Vector3::z()];
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = match (kind, axis) {
        (JointType::Hinge, Some(axis)) => {
            let (p1, p2) = normals(&axis);
            vec![(axis, p1), (axis, p2)]
        }
        // x·y, y·z, z·x of the two frames as they are at t = 0: each is first-order
        // in the relative turn about z, x and y.
        (JointType::Weld | JointType::Prismatic, _) => {
            vec![(e[0], e[1]), (e[1], e[2]), (e[2], e[0])]
        }
        _ => Vec::new(),
    };
    for (k, (u, v)) in pairs.into_iter().enumerate() {
        rows.push(row(
            first + k,
            RowKind::Align(Box::new(AlignAxes {
                u: ra.inverse() * u,
                v: in_b(v),
            })),
        ));
    }
    Ok(rows)
}

/// Two unit vectors normal to the unit `axis` and to each other: the first from the
/// world axis least aligned with it (a fixed rule, so the rows do not depend on round-
/// off), the second `axis × first`.
fn normals(axis: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = axis.map(f64::abs);
    let e = if a.x <= a.y && a.x <= a.z {
        Vector3::x()
    } else if a.y <= a.z {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let p1 = axis.cross(&e).normalize();
    (p1, axis.cross(&p1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hinges_normals_are_orthonormal_to_its_axis() {
        for axis in [
            Vector3::z(),
            Vector3::new(1.0, 2.0, -3.0).normalize(),
            Vector3::x(),
        ] {
            let (p1, p2) = normals(&axis);
            for (x, y) in [(p1, axis), (p2, axis), (p1, p2)] {
                assert!(x.dot(&y).abs() < 1e-15);
            }
            assert!((p1.norm() - 1.0).abs() < 1e-15 && (p2.norm() - 1.0).abs() < 1e-15);
        }
    }
}
