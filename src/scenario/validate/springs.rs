//! `model.springs`: linear spring-dampers, force elements between two bodies' anchors
//! or a body's anchor and a world point.

use super::bodies::Ids;
use super::checks::{magnitude, magnitude_vector, non_negative, num};
use crate::error::{Error, Result};
use crate::scenario::file::SpringFile;
use crate::scenario::model::{BodySpec, SpringSpec};

/// Most springs a scenario may declare (each is a few vectors of state-free data and a
/// pass per rate evaluation).
pub const MAX_SPRINGS: usize = 100_000;

/// The springs of the file, with their rest lengths (default: the anchors' distance at
/// t = 0, so each starts unloaded).
pub(super) fn springs(
    files: &[SpringFile],
    ids: &Ids,
    bodies: &[BodySpec],
) -> Result<Vec<SpringSpec>> {
    if files.len() > MAX_SPRINGS {
        return Err(Error::invalid(
            "model.springs",
            format!(
                "has {} springs; at most {MAX_SPRINGS} are allowed",
                files.len()
            ),
        ));
    }
    files
        .iter()
        .enumerate()
        .map(|(i, f)| spring(&format!("model.springs[{i}]"), f, ids, bodies))
        .collect()
}

fn spring(path: &str, f: &SpringFile, ids: &Ids, bodies: &[BodySpec]) -> Result<SpringSpec> {
    let a = ids.index(&format!("{path}.a"), f.a)?;
    let b = match f.b {
        Some(id) => {
            let b = ids.index(&format!("{path}.b"), id)?;
            if b == a {
                return Err(Error::invalid(
                    format!("{path}.b"),
                    format!("a spring cannot join body {id} to itself"),
                ));
            }
            Some(b)
        }
        None => None,
    };
    let anchor_a = magnitude_vector(&format!("{path}.anchor_a"), f.anchor_a)?;
    let anchor_b = magnitude_vector(&format!("{path}.anchor_b"), f.anchor_b)?;
    let stiffness = magnitude(
        &format!("{path}.stiffness"),
        non_negative(&format!("{path}.stiffness"), f.stiffness)?,
    )?;
    let damping = magnitude(
        &format!("{path}.damping"),
        non_negative(&format!("{path}.damping"), f.damping)?,
    )?;
    // The anchors' world points at t = 0.
    let world = |i: usize, r| {
        let body = &bodies[i];
        body.position + body.orientation * r
    };
    let pa = world(a, anchor_a);
    let pb = b.map_or(anchor_b, |b| world(b, anchor_b));
    let length = match f.length {
        Some(l) => magnitude(
            &format!("{path}.length"),
            non_negative(&format!("{path}.length"), l)?,
        )?,
        None => (pa - pb).norm(),
    };
    if length == 0.0 && (pa - pb).norm() == 0.0 {
        // Both anchors on one point with no rest length: the force's direction is
        // undefined at the start (a zero-length spring must start stretched).
        return Err(Error::invalid(
            format!("{path}.length"),
            format!(
                "a spring of rest length 0 must start stretched: its anchors coincide at \
                 t = 0 (at [{}, {}, {}])",
                num(pa.x),
                num(pa.y),
                num(pa.z)
            ),
        ));
    }
    Ok(SpringSpec {
        a,
        b,
        anchor_a,
        anchor_b,
        stiffness,
        damping,
        length,
    })
}
