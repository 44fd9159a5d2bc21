//! `sweep.csv` and `timing.csv` from the points' records.
//!
//! `sweep.csv` columns: `index`, `point` (the point's directory under `points/`), one
//! per axis, `rep` (with `repeat` > 1), `seed`,
//! `status`, `diverged_at` [s], `diverged_node`, `diverged_where` (the link `L14` or body
//! `B3`; the three are empty for a point that finished), `mean_cost`,
//! `unpaired_mean_cost_<method>` for every method any record has (sorted), for every baseline
//! any record compares with (sorted) the paired columns `paired_<c>_<baseline>`
//! ([`super::points::PAIRED_COLUMNS`]), `lost_frames`,
//! `tau_<name>_requested,tau_<name>_achieved` for every channel any record has (in order
//! of first appearance by index), `bandwidth`, `digest`. Numbers are in Rust's shortest
//! round-trip form; a value a run did not produce is an empty field. An axis column
//! holds the value's label ([`super::points::Axis::label`]): the sweep file's `labels`
//! entry, else a number as it is, else a string's text — never JSON, so every column
//! loads into a typed column (pandas, R, a spreadsheet).
//!
//! Wall time is not in `sweep.csv` (which is a pure function of the sweep and the
//! binary); it is in `timing.csv` (`index,wall_seconds`).
//!
//! Both are written with the `csv` crate (text fields quoted only where needed); the
//! numbers are formatted here, see [`csv_text`].

use std::collections::BTreeSet;

use super::points::{
    Plan, LEADING_COLUMNS, LOSS_COLUMN, PAIRED_COLUMNS, STATUS_COLUMNS, TRAILING_COLUMNS,
};
use super::record::Record;
use crate::output::csv_text;

/// A number field: shortest round-trip form, empty for none.
fn num(x: Option<f64>) -> String {
    match x {
        Some(x) if x.is_finite() => format!("{x}"),
        _ => String::new(),
    }
}

/// `sweep.csv` of `records` (sorted by index).
pub fn sweep_csv(plan: &Plan, records: &[Record]) -> String {
    let methods: BTreeSet<&str> = records
        .iter()
        .flat_map(|r| {
            r.row
                .unpaired_mean_cost_by_method
                .keys()
                .map(String::as_str)
        })
        .collect();
    let paired: BTreeSet<&str> = records
        .iter()
        .flat_map(|r| r.row.paired.keys().map(String::as_str))
        .collect();
    let mut channels: Vec<&str> = Vec::new();
    for r in records {
        for c in &r.row.channels {
            if !channels.contains(&c.name.as_str()) {
                channels.push(&c.name);
            }
        }
    }
    let mut header: Vec<String> = LEADING_COLUMNS.map(String::from).to_vec();
    header.extend(plan.axes.iter().map(|a| a.name.clone()));
    if plan.repeat > 1 {
        header.push("rep".into());
    }
    header.extend(STATUS_COLUMNS.map(String::from));
    header.extend(methods.iter().map(|m| format!("unpaired_mean_cost_{m}")));
    for m in &paired {
        header.extend(PAIRED_COLUMNS.map(|c| format!("paired_{c}_{m}")));
    }
    header.push(LOSS_COLUMN.into());
    for c in &channels {
        header.push(format!("tau_{c}_requested"));
        header.push(format!("tau_{c}_achieved"));
    }
    header.extend(TRAILING_COLUMNS.map(String::from));
    let mut rows = vec![header];
    for r in records {
        let row = &r.row;
        let mut f = vec![r.index.to_string(), plan.key(r.index)];
        let idx = &plan.points[r.index];
        f.extend(plan.axes.iter().zip(idx).map(|(a, &v)| a.label(v)));
        if plan.repeat > 1 {
            f.push(plan.rep(r.index).to_string());
        }
        f.push(r.seed.to_string());
        f.push(row.status.clone());
        let d = row.divergence.as_ref();
        f.push(num(d.and_then(|d| d.time)));
        f.push(
            d.and_then(|d| d.node)
                .map_or(String::new(), |n| n.to_string()),
        );
        f.push(d.and_then(|d| d.place.clone()).unwrap_or_default());
        f.push(num(row.mean_cost));
        f.extend(
            methods
                .iter()
                .map(|m| num(row.unpaired_mean_cost_by_method.get(*m).copied().flatten())),
        );
        for m in &paired {
            let p = row.paired.get(*m).cloned().unwrap_or_default();
            let count = |c: Option<u64>| c.map_or(String::new(), |c| c.to_string());
            let ci = |i: usize| num(p.ci95.map(|c| c[i]));
            f.extend([
                num(p.ratio),
                count(p.n),
                count(p.wins),
                count(p.losses),
                num(p.mean_difference),
                ci(0),
                ci(1),
                num(p.sign_test_p),
                p.verdict.unwrap_or_default(),
            ]);
        }
        f.push(row.lost_frames.to_string());
        for name in &channels {
            let c = row.channels.iter().find(|c| c.name == *name);
            f.push(num(c.and_then(|c| c.tau_requested)));
            f.push(num(c.and_then(|c| c.tau_achieved)));
        }
        f.push(num(row.bandwidth));
        f.push(row.digest.clone());
        rows.push(f);
    }
    csv_text(rows)
}

/// `timing.csv`: `index,wall_seconds` per record.
pub fn timing_csv(records: &[Record]) -> String {
    let header = ["index".to_string(), "wall_seconds".to_string()];
    let rows = records
        .iter()
        .map(|r| [r.index.to_string(), num(Some(r.wall_seconds))]);
    csv_text(std::iter::once(header).chain(rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::file::parse;
    use crate::sweep::points::plan;
    use crate::sweep::record::DivergenceRow;
    use crate::sweep::record::{ChannelRow, Row};
    use serde_json::{json, Value};
    use std::collections::BTreeMap;

    fn record(index: usize, values: Vec<Value>, methods: &[(&str, f64)], channel: &str) -> Record {
        Record {
            index,
            values,
            seed: 10 + index as u64,
            scenario_digest: "s".into(),
            base_digest: "b".into(),
            row: Row {
                status: "ok".into(),
                divergence: None,
                mean_cost: Some(0.5),
                unpaired_mean_cost_by_method: methods
                    .iter()
                    .map(|&(m, c)| (m.to_string(), Some(c)))
                    .collect::<BTreeMap<_, _>>(),
                paired: BTreeMap::new(),
                live_method: None,
                lost_frames: 0,
                channels: vec![ChannelRow {
                    name: channel.into(),
                    tau_requested: Some(0.005),
                    tau_achieved: None,
                }],
                bandwidth: Some(400.0),
                digest: "d".into(),
            },
            wall_seconds: 0.25,
        }
    }

    #[test]
    fn columns_are_the_union_and_values_are_quoted() {
        let p = plan(
            &parse(
                r#"{"name": "s", "base": "b", "axes": [
                {"name": "slots", "pointer": "/a", "values": [[1, 2], "x"],
                 "labels": ["one, two", "x"]}]}"#,
                "s",
            )
            .unwrap(),
        )
        .unwrap();
        let mut rows = [
            record(0, vec![json!([1, 2])], &[("grid", 0.25)], "c1"),
            record(1, vec![json!("x")], &[("dsm", 0.125)], "c2"),
        ];
        rows[1].row.status = "diverged".into();
        rows[1].row.divergence = Some(DivergenceRow {
            time: Some(3.12),
            node: Some(2),
            place: Some("L14".into()),
        });
        let (k0, k1) = (p.key(0), p.key(1));
        assert_eq!(
            sweep_csv(&p, &rows),
            format!(
                "index,point,slots,seed,status,diverged_at,diverged_node,diverged_where,mean_cost,\
             unpaired_mean_cost_dsm,unpaired_mean_cost_grid,lost_frames,\
             tau_c1_requested,tau_c1_achieved,tau_c2_requested,tau_c2_achieved,bandwidth,digest\n\
             0,{k0},\"one, two\",10,ok,,,,0.5,,0.25,0,0.005,,,,400,d\n\
             1,{k1},x,11,diverged,3.12,2,L14,0.5,0.125,,0,,,0.005,,400,d\n"
            )
        );
        assert_eq!(timing_csv(&rows), "index,wall_seconds\n0,0.25\n1,0.25\n");
    }

    #[test]
    fn each_paired_comparison_has_its_columns_and_a_run_without_it_leaves_them_empty() {
        let p = plan(
            &parse(
                r#"{"name": "s", "base": "b", "axes": [
                {"name": "size", "pointer": "/a", "values": [1, 2]}]}"#,
                "s",
            )
            .unwrap(),
        )
        .unwrap();
        let mut rows = [
            record(0, vec![json!(1)], &[], "c"),
            record(1, vec![json!(2)], &[], "c"),
        ];
        rows[0].row.paired.insert(
            "no_opt".into(),
            crate::sweep::record::PairedRow {
                n: Some(30),
                wins: Some(20),
                losses: Some(10),
                ratio: Some(0.875),
                mean_difference: Some(-0.25),
                ci95: Some([-0.5, 0.125]),
                sign_test_p: Some(0.0625),
                verdict: Some("not_significant".into()),
            },
        );
        let csv = sweep_csv(&p, &rows);
        let mut lines = csv.lines();
        let header = lines.next().unwrap();
        assert!(header.contains(
            "mean_cost,paired_ratio_no_opt,paired_n_no_opt,paired_wins_no_opt,\
             paired_losses_no_opt,paired_diff_no_opt,paired_ci_low_no_opt,\
             paired_ci_high_no_opt,paired_p_no_opt,paired_verdict_no_opt,lost_frames"
        ));
        assert!(lines
            .next()
            .unwrap()
            .contains(",0.5,0.875,30,20,10,-0.25,-0.5,0.125,0.0625,not_significant,0,"));
        assert!(lines.next().unwrap().contains(",0.5,,,,,,,,,,0,"));
    }
}
