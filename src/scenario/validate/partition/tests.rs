//! Quadrant layouts and link ownership against method §3.

use crate::scenario::{parse_str, Scenario};

/// A `rows × cols` thesis-style grid with the given `partition` and `channels`.
fn grid(rows: u32, cols: u32, partition: &str, channels: &str) -> Scenario {
    let text = format!(
        r#"{{"name": "p", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {{"grid": {{"rows": {rows}, "cols": {cols}, "spacing": 1.8,
                                 "mass": 1.0, "size": 0.2}}}},
            "partition": {partition},
            "channels": {channels}}}"#
    );
    match parse_str(&text, "test.json") {
        Ok(s) => s,
        Err(e) => panic!("expected a valid scenario, got: {e}"),
    }
}

/// The thesis space distribution: τ1 on borders 1–2 and 1–4, τ2 on 2–3 and 3–4.
const SPACE: &str = r#"[
    {"name": "tau1", "tau": 0.005, "borders": [[1, 2], [1, 4]]},
    {"name": "tau2", "tau": 0.01, "borders": [[2, 3], [4, 3]]}]"#;

/// The thesis layout written out.
const THESIS_NODES: &str = "[[1, 2, 5, 6], [3, 4, 7, 8], [11, 12, 15, 16], [9, 10, 13, 14]]";

/// Owner (1-based) of the link between body ids `a` and `b`.
fn owner(s: &Scenario, a: u32, b: u32) -> usize {
    let p = s.partition.as_ref().unwrap();
    let k = s
        .links
        .iter()
        .position(|l| {
            let ends = (s.bodies[l.a].id, s.bodies[l.b].id);
            ends == (a, b) || ends == (b, a)
        })
        .unwrap_or_else(|| panic!("no link {a}–{b}"));
    p.link_owner[k] + 1
}

/// Border links as (body id, body id, owner node 1-based), in link order.
fn border_links(s: &Scenario) -> Vec<(u32, u32, usize)> {
    let p = s.partition.as_ref().unwrap();
    s.links
        .iter()
        .zip(&p.link_owner)
        .filter(|(l, _)| p.node_of[l.a] != p.node_of[l.b])
        .map(|(l, &o)| (s.bodies[l.a].id, s.bodies[l.b].id, o + 1))
        .collect()
}

/// The ring ownership of method §3, by body-id pairs.
const RING: [(u32, u32, usize); 8] = [
    (2, 3, 1),
    (6, 7, 1),
    (7, 11, 2),
    (8, 12, 2),
    (11, 10, 3),
    (15, 14, 3),
    (9, 5, 4),
    (10, 6, 4),
];

#[test]
fn thesis_quadrants_are_the_ring_of_spec_section_3() {
    let s = grid(4, 4, r#"{"quadrants": true}"#, SPACE);
    let p = s.partition.as_ref().unwrap();
    assert_eq!(p.nodes, 4);
    let node = |id: u32| p.node_of[id as usize - 1];
    for (n, ids) in [
        [1, 2, 5, 6],
        [3, 4, 7, 8],
        [11, 12, 15, 16],
        [9, 10, 13, 14],
    ]
    .iter()
    .enumerate()
    {
        for &id in ids {
            assert_eq!(node(id), n, "body {id}");
        }
    }
    for (a, b, n) in RING {
        assert_eq!(owner(&s, a, b), n, "border link {a}–{b}");
    }
    assert_eq!(border_links(&s).len(), 8);
    for n in 0..4 {
        let owned = p.link_owner.iter().filter(|&&o| o == n).count();
        assert_eq!(owned, 6, "links owned by node {}", n + 1);
    }
    // Internal links belong to their node.
    assert_eq!(owner(&s, 1, 2), 1);
    assert_eq!(owner(&s, 15, 16), 3);
    assert_eq!(p.ghosts, crate::scenario::model::GhostMode::Integrate);
}

#[test]
fn larger_quadrants_are_numbered_row_by_row_and_owned_by_the_lower_body() {
    let s = grid(
        8,
        8,
        r#"{"quadrants": true, "ghosts": "hold"}"#,
        "[{\"name\": \"all\", \"tau\": 0.002}]",
    );
    let p = s.partition.as_ref().unwrap();
    assert_eq!(p.nodes, 16);
    for (i, &n) in p.node_of.iter().enumerate() {
        let (r, c) = (i / 8, i % 8);
        assert_eq!(n, (r / 2) * 4 + c / 2, "body {}", i + 1);
    }
    for n in 0..16 {
        assert_eq!(p.node_of.iter().filter(|&&m| m == n).count(), 4);
    }
    for (l, &o) in s.links.iter().zip(&p.link_owner) {
        assert_eq!(o, p.node_of[l.a.min(l.b)]);
    }
    // A +x link from an odd column (1, 3, 5) or a +y link from an odd row crosses a
    // block boundary: 3 per row or column, 8 rows and 8 columns.
    assert_eq!(border_links(&s).len(), 3 * 8 + 3 * 8);
    assert_eq!(p.ghosts, crate::scenario::model::GhostMode::Hold);
}

#[test]
fn explicit_thesis_nodes_need_overrides_to_give_the_ring() {
    let quadrants = grid(4, 4, r#"{"quadrants": true}"#, SPACE);
    let plain = grid(4, 4, &format!(r#"{{"nodes": {THESIS_NODES}}}"#), SPACE);
    let (q, e) = (
        quadrants.partition.as_ref().unwrap(),
        plain.partition.as_ref().unwrap(),
    );
    assert_eq!(e.node_of, q.node_of);
    // The general rule gives a border link to the node of its lower-numbered body:
    // the ring's 11–10, 15–14 (node 3) and 9–5, 10–6 (node 4) go the other way.
    for (a, b, ring, general) in [(11, 10, 3, 4), (15, 14, 3, 4), (9, 5, 4, 1), (10, 6, 4, 1)] {
        assert_eq!(owner(&quadrants, a, b), ring, "{a}–{b}");
        assert_eq!(owner(&plain, a, b), general, "{a}–{b}");
    }
    for (a, b, n) in [(2, 3, 1), (6, 7, 1), (7, 11, 2), (8, 12, 2)] {
        assert_eq!(owner(&plain, a, b), n, "{a}–{b}");
    }
    // Links 9 = 5–9, 11 = 6–10, 17 = 10–11, 23 = 14–15 (grid numbering).
    let overridden = grid(
        4,
        4,
        &format!(
            r#"{{"nodes": {THESIS_NODES}, "link_owners": [
                {{"link": 9, "node": 4}}, {{"link": 11, "node": 4}},
                {{"link": 17, "node": 3}}, {{"link": 23, "node": 3}}]}}"#
        ),
        SPACE,
    );
    assert_eq!(overridden.partition, quadrants.partition);
}

#[test]
fn one_node_needs_no_channels_and_overrides_apply_to_quadrants() {
    let s = grid(2, 3, r#"{"nodes": [[1, 2, 3, 4, 5, 6]]}"#, "[]");
    let p = s.partition.as_ref().unwrap();
    assert_eq!((p.nodes, p.link_owner.clone()), (1, vec![0; 7]));
    assert!(s.channels.is_empty());
    // Quadrant ring link 3 = 2–3 (node 1 → 2) handed to node 2.
    let s = grid(
        4,
        4,
        r#"{"quadrants": true, "link_owners": [{"link": 3, "node": 2}]}"#,
        SPACE,
    );
    assert_eq!(owner(&s, 2, 3), 2);
    assert_eq!(owner(&s, 6, 7), 1);
    // A 4×2 grid is one column of two blocks: nodes by block row, no ring.
    let s = grid(
        4,
        2,
        r#"{"quadrants": true}"#,
        r#"[{"name": "c", "tau": 0.001}]"#,
    );
    let p = s.partition.as_ref().unwrap();
    assert_eq!(
        (p.nodes, p.node_of.clone()),
        (2, vec![0, 0, 0, 0, 1, 1, 1, 1])
    );
    assert_eq!(border_links(&s), vec![(3, 5, 1), (4, 6, 1)]);
}

#[test]
fn the_general_rule_goes_by_body_id_not_by_file_order() {
    // Bodies listed as 5 then 2, the link written 5–2 (and 9–7 beside it), equal
    // masses and one constraint each: body 2 is the lower-numbered one, so its node
    // (node 1 = [2]) owns the border link, whatever the file order.
    let text = r#"{"name": "p", "seed": 1, "duration": 1.0, "dt": 0.001,
        "model": {
          "bodies": [{"id": 5, "mass": 1.0, "size": 0.2, "position": [1.8, 0, 0]},
                     {"id": 2, "mass": 1.0, "size": 0.2, "position": [0, 0, 0]},
                     {"id": 9, "mass": 1.0, "size": 0.2, "position": [3.6, 0, 0]},
                     {"id": 7, "mass": 1.0, "size": 0.2, "position": [5.4, 0, 0]}],
          "links": [{"a": 5, "b": 2}, {"a": 9, "b": 7}]},
        "partition": {"nodes": [[2], [5], [9], [7]]},
        "channels": [{"name": "c", "tau": 0.001}]}"#;
    let s = match parse_str(text, "test.json") {
        Ok(s) => s,
        Err(e) => panic!("expected a valid scenario, got: {e}"),
    };
    assert_eq!(owner(&s, 5, 2), 1, "5–2 belongs to body 2's node");
    assert_eq!(owner(&s, 9, 7), 4, "9–7 belongs to body 7's node");
}

/// A chain of three bodies on three nodes with the given masses.
fn chain3(masses: [f64; 3]) -> Scenario {
    let bodies: Vec<String> = masses
        .iter()
        .enumerate()
        .map(|(i, m)| {
            format!(
                r#"{{"id": {}, "mass": {m}, "size": 0.2, "position": [{}, 0, 0]}}"#,
                i + 1,
                i as f64 * 1.8
            )
        })
        .collect();
    let text = format!(
        r#"{{"name": "c", "seed": 1, "duration": 1.0, "dt": 0.001,
            "model": {{"bodies": [{}], "links": [{{"a": 1, "b": 2}}, {{"a": 2, "b": 3}}]}},
            "partition": {{"nodes": [[1], [2], [3]]}},
            "channels": [{{"name": "all", "tau": 0.005}}]}}"#,
        bodies.join(", ")
    );
    parse_str(&text, "chain.json").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_border_link_belongs_to_the_side_driven_hardest_by_its_other_constraints() {
    // Equal masses: the end body (no other constraint) is the far side, so the middle
    // body's node owns both links, as the lower-id rule gives for 1–2 and not for 2–3.
    let s = chain3([1.0, 1.0, 1.0]);
    assert_eq!((owner(&s, 1, 2), owner(&s, 2, 3)), (2, 2));
    // A light middle body between heavy ends owns both links; a heavy middle body
    // still owns them (1 other constraint per 100 kg against none).
    let s = chain3([100.0, 0.01, 100.0]);
    assert_eq!((owner(&s, 1, 2), owner(&s, 2, 3)), (2, 2));
    let s = chain3([0.01, 100.0, 0.01]);
    assert_eq!((owner(&s, 1, 2), owner(&s, 2, 3)), (2, 2));
    // Every border link of the alternating 100 kg / 0.01 kg grid is its light body's.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenarios/mechanisms/grid16_mass_ratio.json"),
    )
    .expect("scene");
    let s = parse_str(&text, "grid16_mass_ratio.json").expect("valid");
    let p = s.partition.as_ref().unwrap();
    let borders = border_links(&s);
    assert_eq!(borders.len(), 8);
    for (a, b, n) in borders {
        let light = if s.bodies[a as usize - 1].mass < s.bodies[b as usize - 1].mass {
            a
        } else {
            b
        };
        assert_eq!(n, p.node_of[light as usize - 1] + 1, "border link {a}–{b}");
    }
}
