//! The model stage: a grid is expanded, bodies and links are checked, ids resolve to
//! indices and the body model (`auto` → point masses or rigid bodies) is chosen.

use std::collections::BTreeMap;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::checks::{finite, num, positive, positive_magnitude, vec_str, vector, MAGNITUDE};
use crate::error::{Error, Result};
use crate::scenario::file::{BodyFile, BodyModelFile, LinkFile, ModelFile};
use crate::scenario::grid;
use crate::scenario::model::{BodyModel, BodySpec, LinkSpec, RowKind};

/// The validated model section.
pub(super) struct Model {
    /// Bodies in file order (a grid row by row).
    pub bodies: Vec<BodySpec>,
    /// Links in file order.
    pub links: Vec<LinkSpec>,
    /// The body model after resolving `auto`.
    pub body_model: BodyModel,
    /// Body id → index, for the sections that name bodies.
    pub ids: Ids,
}

/// Validates `model` (exactly one of `grid` or `bodies` + `links`) and resolves
/// `body_model`.
///
/// `loads` names the first load field that needs rotation (a force off the centre, a
/// torque), if any: `auto` then chooses rigid bodies, and `point_mass` is refused.
pub(super) fn model(
    model: &ModelFile,
    choice: BodyModelFile,
    loads: Option<(String, Vec<f64>)>,
    fmus_only: bool,
) -> Result<Model> {
    // Expand a grid into the explicit form, so both kinds of model validate alike.
    let (body_files, link_files) = match (&model.grid, &model.bodies, &model.links) {
        (Some(g), None, None) => grid::expand(g, "model.grid")?,
        (Some(_), _, _) => {
            return Err(Error::invalid(
                "model",
                "give either `grid` or `bodies` (with `links`), not both",
            ))
        }
        (None, Some(bodies), links) => (bodies.clone(), links.clone().unwrap_or_default()),
        (None, None, Some(_)) => {
            return Err(Error::invalid(
                "model.links",
                "needs `bodies` (a grid generates its own links)",
            ))
        }
        // A scene of FMUs only: no bodies, no links.
        (None, None, None) if fmus_only => (Vec::new(), Vec::new()),
        (None, None, None) => {
            return Err(Error::invalid(
                "model",
                "needs either `grid` or `bodies` (or leave `model` out in a scene of \
                 `fmus` only)",
            ))
        }
    };
    if body_files.is_empty() && !fmus_only {
        return Err(Error::invalid(
            "model.bodies",
            "must list at least one body",
        ));
    }

    let mut ids = BTreeMap::new();
    let mut bodies = Vec::with_capacity(body_files.len());
    for (i, b) in body_files.iter().enumerate() {
        let path = format!("model.bodies[{i}]");
        if let Some(first) = ids.insert(b.id, i) {
            return Err(Error::invalid(
                format!("{path}.id"),
                format!("duplicate id {} (also model.bodies[{first}].id)", b.id),
            ));
        }
        bodies.push(body(&path, b)?);
    }
    let ids = Ids(ids);
    let links = link_files
        .iter()
        .enumerate()
        .map(|(i, l)| link(&format!("model.links[{i}]"), l, &ids, &bodies))
        .collect::<Result<Vec<_>>>()?;
    no_duplicate_links(&links, &link_files)?;
    let body_model = body_model(choice, &body_files, &link_files, loads)?;
    Ok(Model {
        bodies,
        links,
        body_model,
        ids,
    })
}

/// Body id → index into the body list.
pub(super) struct Ids(BTreeMap<u32, usize>);

impl Ids {
    /// The index of body `id`; `path` names the field that refers to it.
    pub(super) fn index(&self, path: &str, id: u32) -> Result<usize> {
        self.0
            .get(&id)
            .copied()
            .ok_or_else(|| Error::invalid(path, format!("no body with id {id}")))
    }
}

/// Refuses a link that joins the same two bodies at the same anchors as an earlier one
/// (in either direction): its constraint is the earlier one's again, so `J M⁻¹ Jᵀ` is
/// singular — the exact solve stopped at t = 0 naming no link, CG ran on. Two links
/// between the same bodies at other anchors (a hinge of rigid bodies) are fine.
fn no_duplicate_links(links: &[LinkSpec], files: &[LinkFile]) -> Result<()> {
    // The ends in body order with their anchors (bit for bit).
    let ends = |l: &LinkSpec| {
        let bits = |v: &Vector3<f64>| v.map(f64::to_bits);
        let (ea, eb) = ((l.a, bits(&l.anchor_a)), (l.b, bits(&l.anchor_b)));
        if ea.0 <= eb.0 {
            (ea, eb)
        } else {
            (eb, ea)
        }
    };
    // Links sorted by their pair of bodies (24 bytes a link: a million-body grid's two
    // million links take 48 MB here, freed before the run), then each run of links
    // between the same pair compared by anchors.
    let mut pairs: Vec<(usize, usize, usize)> = links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.a.min(l.b), l.a.max(l.b), i))
        .collect();
    pairs.sort_unstable();
    for run in pairs.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        for (k, &(_, _, i)) in run.iter().enumerate() {
            let Some(&(_, _, first)) = run[..k]
                .iter()
                .find(|&&(_, _, j)| ends(&links[j]) == ends(&links[i]))
            else {
                continue;
            };
            return Err(Error::invalid(
                format!("model.links[{i}]"),
                format!(
                    "joins bodies {} and {} at the same anchors as model.links[{first}]; a \
                     constraint given twice makes J M⁻¹ Jᵀ singular (remove one)",
                    files[i].a, files[i].b
                ),
            ));
        }
    }
    Ok(())
}

/// One body: checked values, defaults applied.
fn body(path: &str, b: &BodyFile) -> Result<BodySpec> {
    let mass = positive_magnitude(&format!("{path}.mass"), b.mass)?;
    let size = positive(&format!("{path}.size"), b.size)?;
    let inertia = match b.inertia {
        Some(moments) => {
            for (i, &m) in moments.iter().enumerate() {
                positive_magnitude(&format!("{path}.inertia[{i}]"), m)?;
            }
            Vector3::from(moments)
        }
        None => {
            let cube = mass * size * size / 6.0;
            if !(cube.is_finite() && (1.0 / MAGNITUDE..=MAGNITUDE).contains(&cube)) {
                return Err(Error::invalid(
                    format!("{path}.inertia"),
                    format!(
                        "the cube default m s²/6 is {} for mass {} and size {}; give it \
                         explicitly",
                        num(cube),
                        num(mass),
                        num(size)
                    ),
                ));
            }
            Vector3::repeat(cube)
        }
    };
    Ok(BodySpec {
        id: b.id,
        mass,
        size,
        inertia,
        position: vector(&format!("{path}.position"), b.position)?,
        velocity: vector(&format!("{path}.velocity"), b.velocity)?,
        orientation: unit_quaternion(&format!("{path}.orientation"), b.orientation)?,
        angular_velocity: vector(&format!("{path}.angular_velocity"), b.angular_velocity)?,
    })
}

/// Normalizes a `[w, x, y, z]` quaternion; zero (or non-finite) is an error.
fn unit_quaternion(path: &str, q: [f64; 4]) -> Result<UnitQuaternion<f64>> {
    for (i, &x) in q.iter().enumerate() {
        finite(&format!("{path}[{i}]"), x)?;
    }
    let quaternion = Quaternion::new(q[0], q[1], q[2], q[3]);
    let norm = quaternion.norm();
    if norm.is_finite() && norm >= f64::MIN_POSITIVE.sqrt() {
        return Ok(UnitQuaternion::new_normalize(quaternion));
    }
    // Tiny or huge components: the squared norm under- or overflows, so scale first.
    let scale = q.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if scale == 0.0 {
        return Err(Error::invalid(
            path,
            "must not be the zero quaternion (got [0, 0, 0, 0])",
        ));
    }
    Ok(UnitQuaternion::new_normalize(quaternion / scale))
}

/// One link: ids resolved, length defaulted to the initial anchor distance.
fn link(path: &str, l: &LinkFile, ids: &Ids, bodies: &[BodySpec]) -> Result<LinkSpec> {
    let a = ids.index(&format!("{path}.a"), l.a)?;
    let b = ids.index(&format!("{path}.b"), l.b)?;
    if a == b {
        return Err(Error::invalid(
            format!("{path}.b"),
            format!("a link cannot join body {} to itself", l.b),
        ));
    }
    let anchor_a = vector(&format!("{path}.anchor_a"), l.anchor_a)?;
    let anchor_b = vector(&format!("{path}.anchor_b"), l.anchor_b)?;
    let length_path = format!("{path}.length");
    let length = match l.length {
        Some(length) => positive(&length_path, length)?,
        None => {
            // The default: the initial distance between the anchors in world coordinates.
            let world =
                |body: &BodySpec, anchor: &Vector3<f64>| body.position + body.orientation * anchor;
            let d = (world(&bodies[a], &anchor_a) - world(&bodies[b], &anchor_b)).norm();
            if !(d.is_finite() && d > 0.0) {
                let why = if d == 0.0 {
                    format!(" (the anchors of bodies {} and {} coincide)", l.a, l.b)
                } else {
                    String::new()
                };
                return Err(Error::invalid(
                    length_path,
                    format!(
                        "defaults to the initial distance between the anchors, which is {} \
                         m{why}; give a length",
                        num(d)
                    ),
                ));
            }
            d
        }
    };
    Ok(LinkSpec {
        a,
        b,
        length,
        anchor_a,
        anchor_b,
        kind: RowKind::Distance,
        world: false,
        joint: None,
    })
}

/// Resolves `body_model`; an explicit `"point_mass"` must not need rotation.
fn body_model(
    choice: BodyModelFile,
    bodies: &[BodyFile],
    links: &[LinkFile],
    loads: Option<(String, Vec<f64>)>,
) -> Result<BodyModel> {
    // The first field that makes rotation matter, if any.
    let needs_rotation = || -> Option<(String, Vec<f64>)> {
        if let Some(load) = &loads {
            return Some(load.clone());
        }
        for (i, l) in links.iter().enumerate() {
            for (key, anchor) in [("anchor_a", l.anchor_a), ("anchor_b", l.anchor_b)] {
                if anchor != [0.0; 3] {
                    return Some((format!("model.links[{i}].{key}"), anchor.to_vec()));
                }
            }
        }
        bodies.iter().enumerate().find_map(|(i, b)| {
            (b.angular_velocity != [0.0; 3]).then(|| {
                (
                    format!("model.bodies[{i}].angular_velocity"),
                    b.angular_velocity.to_vec(),
                )
            })
        })
    };
    match choice {
        BodyModelFile::Rigid => Ok(BodyModel::Rigid),
        BodyModelFile::Auto => Ok(match needs_rotation() {
            Some(_) => BodyModel::Rigid,
            None => BodyModel::PointMass,
        }),
        BodyModelFile::PointMass => match needs_rotation() {
            Some((path, value)) => Err(Error::invalid(
                path,
                format!(
                    "must be [0, 0, 0] with body_model \"point_mass\" (got {}); use \"rigid\" \
                     or \"auto\"",
                    vec_str(&value)
                ),
            )),
            None => Ok(BodyModel::PointMass),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternions_are_normalized_whatever_their_scale() {
        for scale in [1e-200, 1.0, 2.0, 1e200] {
            assert_eq!(
                unit_quaternion("q", [scale, 0.0, 0.0, 0.0]).unwrap(),
                UnitQuaternion::identity(),
                "scale {scale}"
            );
        }
        let q = unit_quaternion("q", [1.0, 1.0, 0.0, 0.0]).unwrap();
        assert!((q.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert_eq!(
            unit_quaternion("q", [0.0; 4]).unwrap_err().to_string(),
            "q: must not be the zero quaternion (got [0, 0, 0, 0])"
        );
    }
}
