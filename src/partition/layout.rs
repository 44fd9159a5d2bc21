//! Ownership, ghosts and message routes of a partitioning.

use crate::scenario::model::{DataKind, Scenario};

/// A message route; defined with the messages it labels ([`crate::network::Route`]), and
/// built here from the partitioning.
pub use crate::network::Route;

/// Who owns what, and what flows where.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Layout {
    /// Number of computing nodes.
    pub nodes: usize,
    /// Node of each body.
    pub node_of: Vec<usize>,
    /// Node owning each link.
    pub link_owner: Vec<usize>,
    /// Bodies owned by each node, in body order.
    pub owned: Vec<Vec<usize>>,
    /// Ghost bodies of each node (far ends of its border links), in body order.
    pub ghosts: Vec<Vec<usize>>,
    /// Links owned by each node, in link order.
    pub links: Vec<Vec<usize>>,
    /// Every route, sorted (kind, from, to, body, link): states of ghosted bodies owner →
    /// ghosting node, one per (body, ghosting node); border-link forces link owner →
    /// body owner, one per border link.
    pub routes: Vec<Route>,
}

impl Layout {
    /// The layout of a scenario (one node when it has no partition).
    pub fn new(s: &Scenario) -> Layout {
        let (nodes, node_of, link_owner) = match &s.partition {
            Some(p) => (p.nodes, p.node_of.clone(), p.link_owner.clone()),
            None => (1, vec![0; s.bodies.len()], vec![0; s.links.len()]),
        };
        let mut owned = vec![Vec::new(); nodes];
        for (b, &n) in node_of.iter().enumerate() {
            owned[n].push(b);
        }
        let mut links = vec![Vec::new(); nodes];
        let mut ghosts = vec![Vec::new(); nodes];
        let mut routes = Vec::new();
        for (l, link) in s.links.iter().enumerate() {
            let owner = link_owner[l];
            links[owner].push(l);
            // A joint's rows share their bodies and owner: its force crosses as one
            // message, on the route of its first row (see `Node::force_payload`).
            let later_row = link.joint.is_some_and(|(_, r)| r > 0);
            for body in [link.a, link.b] {
                let body_node = node_of[body];
                if body_node == owner {
                    continue;
                }
                ghosts[owner].push(body);
                if later_row {
                    continue;
                }
                routes.push(Route {
                    kind: DataKind::Force,
                    from: owner,
                    to: body_node,
                    body,
                    link: Some(l),
                });
            }
        }
        for (n, g) in ghosts.iter_mut().enumerate() {
            g.sort_unstable();
            g.dedup();
            for &body in g.iter() {
                routes.push(Route {
                    kind: DataKind::State,
                    from: node_of[body],
                    to: n,
                    body,
                    link: None,
                });
            }
        }
        routes.sort();
        Layout {
            nodes,
            node_of,
            link_owner,
            owned,
            ghosts,
            links,
            routes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::model::{GhostMode, PartitionSpec};

    fn thesis() -> Scenario {
        let text = r#"{"name": "t", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {"grid": {"rows": 4, "cols": 4, "spacing": 1.8, "mass": 1.0, "size": 0.2}}}"#;
        let mut s = crate::scenario::parse_str(text, "t").unwrap();
        // Thesis quadrants and clockwise border ownership (method §3).
        let node = |id: usize| match id {
            1 | 2 | 5 | 6 => 0,
            3 | 4 | 7 | 8 => 1,
            11 | 12 | 15 | 16 => 2,
            _ => 3,
        };
        let node_of: Vec<usize> = (1..=16).map(node).collect();
        let clockwise = |a: usize, b: usize| {
            let (na, nb) = (node(a), node(b));
            if na == nb || (na + 1) % 4 == nb {
                na
            } else {
                nb
            }
        };
        let link_owner = s
            .links
            .iter()
            .map(|l| clockwise(l.a + 1, l.b + 1))
            .collect();
        s.partition = Some(PartitionSpec {
            nodes: 4,
            node_of,
            link_owner,
            ghosts: GhostMode::Integrate,
            coupling: crate::scenario::model::Coupling::Reset,
        });
        s
    }

    #[test]
    fn thesis_quadrants_give_six_bodies_and_six_links_per_node() {
        let l = Layout::new(&thesis());
        for n in 0..4 {
            assert_eq!(l.owned[n].len(), 4, "node {}", n + 1);
            assert_eq!(l.ghosts[n].len(), 2, "node {}", n + 1);
            assert_eq!(l.links[n].len(), 6, "node {}", n + 1);
        }
        // Node 1 ghosts bodies 3 and 7 (far ends of 2–3 and 6–7).
        assert_eq!(l.ghosts[0], vec![2, 6]);
        // 8 border links: 8 force routes and 8 state routes.
        let forces = l
            .routes
            .iter()
            .filter(|r| r.kind == DataKind::Force)
            .count();
        let states = l
            .routes
            .iter()
            .filter(|r| r.kind == DataKind::State)
            .count();
        assert_eq!((forces, states), (8, 8));
        // Every link exists exactly once.
        let mut all: Vec<usize> = l.links.concat();
        all.sort_unstable();
        assert_eq!(all, (0..24).collect::<Vec<_>>());
    }

    #[test]
    fn monolithic_layout_is_one_node_without_routes() {
        let mut s = thesis();
        s.partition = None;
        let l = Layout::new(&s);
        assert_eq!(l.nodes, 1);
        assert!(l.routes.is_empty() && l.ghosts[0].is_empty());
        assert_eq!(l.owned[0].len(), 16);
    }
}
