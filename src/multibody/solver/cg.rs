//! The iterative path: `A = J M⁻¹ Jᵀ` assembled once per solve as a compressed sparse
//! row (CSR) matrix on a pattern computed once per run, then a Jacobi-preconditioned
//! conjugate gradient, warm-started from the previous solution, with a fixed iteration
//! budget.
//!
//! Why assembled: each CG iteration applies `A` once. Matrix-free, that is a scatter of
//! `Jᵀ p` to the bodies (each link adds into two bodies, and consecutive links share a
//! body, so the adds queue behind each other) and a gather per link. Assembled, it is a
//! row-by-row sparse product whose rows are independent, and the assembly (one pass
//! over the same contributions) is paid once per solve instead of once per iteration.
//! Entry `(k, l)` is non-zero only when links `k` and `l` share a body, so the pattern
//! has `links + 2 Σ_bodies C(deg, 2)` entries: the cost stays linear in the links.

use nalgebra::Vector3;

use super::{Geometry, MassData, SolveError};

/// Runs `$body` for `$i` in `0..$m`, in order, with `$lane = $i % LANES` a constant
/// in each copy of the body (the loop is unrolled by `LANES`), so that accumulators
/// indexed by the lane stay in registers. A macro rather than a function taking a
/// closure: the closure was not inlined.
macro_rules! for_lanes {
    ($m:expr, |$i:ident, $lane:ident| $body:block) => {{
        let m: usize = $m;
        let whole = m - m % LANES;
        let mut start = 0;
        while start < whole {
            for $lane in 0..LANES {
                let $i = start + $lane;
                $body
            }
            start += LANES;
        }
        for $i in whole..m {
            let $lane = $i - whole;
            $body
        }
    }};
}

/// One contribution to the entries `(k, l)` and `(l, k)`, `k < l`, of `A` through a body
/// both links hold: `± (n_kᵀ n_l / m + c_kᵀ I⁻¹ c_l)` (`A` is symmetric, so each pair is
/// computed once and written twice).
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
struct Pair {
    /// First link.
    k: u32,
    /// Second link.
    l: u32,
    /// The shared body.
    body: u32,
    /// Position of `(k, l)` in the CSR values.
    kl: u32,
    /// Position of `(l, k)`.
    lk: u32,
    /// The links hold the body on opposite sides (`a` and `b`): the term is subtracted.
    opposite: bool,
    /// Link `k` holds the body as its `b` end (selects `c_b`; rigid path).
    k_is_b: bool,
    /// Link `l` holds the body as its `b` end.
    l_is_b: bool,
}

/// Rows are padded to the widest row's length when that costs at most this fraction
/// of extra entries: every row then runs the same number of multiply-adds (a loop
/// whose trip count never changes, which the branch predictor gets right), and the
/// padding entries are zeros on the row's own diagonal column.
const MAX_PADDING: f64 = 0.25;

/// CG state: the matrix pattern, its values and the iteration vectors.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct Cg {
    max_iterations: usize,
    tolerance: f64,
    /// `A`, assembled per solve.
    a: Csr,
    /// Position of `(k, k)` in `values`.
    diag_slot: Vec<u32>,
    /// Off-diagonal contributions.
    pairs: Vec<Pair>,
    /// `I⁻¹ c_a` and `I⁻¹ c_b` per link (rigid path scratch).
    ic_a: Vec<Vector3<f64>>,
    ic_b: Vec<Vector3<f64>>,
    /// Inverse diagonal of `A` (Jacobi preconditioner; 1 where the diagonal is not > 0).
    inv_diag: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    last_iterations: usize,
    /// The last solve used its whole budget without reaching its tolerance; `r` then
    /// holds its residual.
    at_budget: bool,
}

impl Cg {
    /// The pattern of `A` for links with these ends over `bodies` bodies.
    pub(super) fn new(
        max_iterations: usize,
        tolerance: f64,
        bodies: usize,
        ends: &[(usize, usize)],
    ) -> Cg {
        let m = ends.len();
        // Indices are stored as u32: a scene is far below 4 G links (validation caps it
        // much lower), so the narrowing cannot lose anything.
        let idx = |i: usize| u32::try_from(i).expect("ok: link and body counts fit in u32");
        let mut incident: Vec<Vec<(usize, bool)>> = vec![Vec::new(); bodies];
        for (k, &(a, b)) in ends.iter().enumerate() {
            incident[a].push((k, false));
            incident[b].push((k, true));
        }
        // Pattern: the diagonal and every pair of links sharing a body, by row.
        let mut rows: Vec<Vec<u32>> = (0..m).map(|k| vec![idx(k)]).collect();
        for inc in &incident {
            for &(k, _) in inc {
                for &(l, _) in inc {
                    if k != l {
                        rows[k].push(idx(l));
                    }
                }
            }
        }
        for row in &mut rows {
            row.sort_unstable();
            row.dedup();
        }
        let nnz: usize = rows.iter().map(Vec::len).sum();
        let width = rows.iter().map(Vec::len).max().unwrap_or(0);
        let padded = ((width * m) as f64) <= (1.0 + MAX_PADDING) * nnz as f64;
        if padded {
            for (k, row) in rows.iter_mut().enumerate() {
                row.resize(width, idx(k));
            }
        }
        let mut row_start = Vec::with_capacity(m + 1);
        row_start.push(0);
        let mut cols = Vec::new();
        let mut diag_slot = Vec::with_capacity(m);
        for (k, row) in rows.iter().enumerate() {
            let pos = row
                .binary_search(&idx(k))
                .expect("ok: every row holds its diagonal");
            diag_slot.push(idx(cols.len() + pos));
            cols.extend_from_slice(row);
            row_start.push(idx(cols.len()));
        }
        // Padding repeats the diagonal column after the real entries; a lookup finds
        // the first (real) one because the real part of a row is sorted and unique.
        let slot = |k: usize, l: usize| {
            let (s, e) = (row_start[k] as usize, row_start[k + 1] as usize);
            let real = rows[k].len().min(e - s);
            let pos = cols[s..s + real]
                .iter()
                .position(|&c| c == idx(l))
                .expect("ok: the pattern holds every pair");
            idx(s + pos)
        };
        let mut pairs = Vec::new();
        for (body, inc) in incident.iter().enumerate() {
            for (i, &(k, kb)) in inc.iter().enumerate() {
                for &(l, lb) in &inc[i + 1..] {
                    pairs.push(Pair {
                        k: idx(k),
                        l: idx(l),
                        body: idx(body),
                        kl: slot(k, l),
                        lk: slot(l, k),
                        opposite: kb != lb,
                        k_is_b: kb,
                        l_is_b: lb,
                    });
                }
            }
        }
        // In row order, so the writes of the assembly sweep the values forwards.
        pairs.sort_by_key(|p| (p.kl, p.body));
        Cg {
            max_iterations,
            tolerance,
            a: Csr {
                width: if padded { width } else { 0 },
                row_start,
                values: vec![0.0; cols.len()],
                cols,
            },
            diag_slot,
            pairs,
            ic_a: Vec::new(),
            ic_b: Vec::new(),
            inv_diag: vec![0.0; m],
            r: vec![0.0; m],
            z: vec![0.0; m],
            p: vec![0.0; m],
            ap: vec![0.0; m],
            last_iterations: 0,
            at_budget: false,
        }
    }

    /// Iterations of the last solve.
    pub(super) fn last_iterations(&self) -> usize {
        self.last_iterations
    }

    /// When the last solve stopped at its iteration budget with `|r| > tolerance |b|`:
    /// its residual `r = b − A x` (as CG updates it, one entry per link) and the budget.
    pub(super) fn residual_at_budget(&self) -> Option<(&[f64], usize)> {
        self.at_budget
            .then(|| (&self.r[..self.diag_slot.len()], self.max_iterations))
    }

    /// Fills `values` with `A` at the current geometry, and the preconditioner.
    fn assemble(&mut self, geo: &Geometry, mass: &MassData) {
        self.a.values.fill(0.0);
        let (n, im) = (&geo.n, &mass.inv_mass);
        let rigid = !geo.ca.is_empty();
        if rigid {
            let ii = &mass.inv_inertia;
            self.ic_a.clear();
            self.ic_b.clear();
            for (k, &(a, b)) in geo.ends.iter().enumerate() {
                self.ic_a.push(ii[a] * geo.ca[k]);
                self.ic_b.push(ii[b] * geo.cb[k]);
            }
        }
        for (k, (&(a, b), &s)) in geo.ends.iter().zip(&self.diag_slot).enumerate() {
            let mut d = n[k].dot(&n[k]) * (im[a] + im[b]);
            if rigid {
                d += geo.ca[k].dot(&self.ic_a[k]) + geo.cb[k].dot(&self.ic_b[k]);
            }
            self.a.values[s as usize] = d;
        }
        for p in &self.pairs {
            let (k, l) = (p.k as usize, p.l as usize);
            let mut v = n[k].dot(&n[l]) * im[p.body as usize];
            if rigid {
                let ck = if p.k_is_b { &geo.cb[k] } else { &geo.ca[k] };
                let icl = if p.l_is_b {
                    &self.ic_b[l]
                } else {
                    &self.ic_a[l]
                };
                v += ck.dot(icl);
            }
            let v = if p.opposite { -v } else { v };
            self.a.values[p.kl as usize] += v;
            self.a.values[p.lk as usize] += v;
        }
        for (inv, &s) in self.inv_diag.iter_mut().zip(&self.diag_slot) {
            let d = self.a.values[s as usize];
            *inv = if d > 0.0 { 1.0 / d } else { 1.0 };
        }
    }

    /// `y = A x` at the geometry of the last solve (for tests).
    #[cfg(test)]
    pub(super) fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.a.product(x, y);
    }

    /// Solves `A x = b`, `x` holding the warm start: at most `max_iterations`
    /// iterations, stopping early once `|r| ≤ tolerance |b|`.
    pub(super) fn solve(
        &mut self,
        geo: &Geometry,
        mass: &MassData,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<(), SolveError> {
        self.last_iterations = 0;
        self.at_budget = false;
        let b_norm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        if b_norm == 0.0 {
            x.fill(0.0);
            return Ok(());
        }
        self.assemble(geo, mass);
        self.a.product(x, &mut self.ap);
        let m = b.len();
        let (r, z, p) = (&mut self.r[..m], &mut self.z[..m], &mut self.p[..m]);
        let (ap, inv_diag) = (&self.ap[..m], &self.inv_diag[..m]);
        let (mut rz, mut rr) = ([0.0; LANES], [0.0; LANES]);
        for_lanes!(m, |i, lane| {
            r[i] = b[i] - ap[i];
            z[i] = r[i] * inv_diag[i];
            p[i] = z[i];
            rz[lane] += r[i] * z[i];
            rr[lane] += r[i] * r[i];
        });
        let (mut rz, mut rr) = (sum(rz), sum(rr));
        let goal = self.tolerance * b_norm;
        for it in 0..self.max_iterations {
            if rr.sqrt() <= goal {
                break;
            }
            let pap = self.a.product(&self.p, &mut self.ap);
            // A non-positive (or NaN) curvature means A is singular along p: stop
            // with the best iterate so far and let the robustness term absorb it.
            if pap.is_nan() || pap <= 0.0 {
                break;
            }
            let alpha = rz / pap;
            let (x, p) = (&mut x[..m], &self.p[..m]);
            let (r, z) = (&mut self.r[..m], &mut self.z[..m]);
            let (ap, inv_diag) = (&self.ap[..m], &self.inv_diag[..m]);
            let (mut rz_lanes, mut rr_lanes) = ([0.0; LANES], [0.0; LANES]);
            for_lanes!(m, |i, lane| {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
                z[i] = r[i] * inv_diag[i];
                rz_lanes[lane] += r[i] * z[i];
                rr_lanes[lane] += r[i] * r[i];
            });
            let (rz_new, rr_new) = (sum(rz_lanes), sum(rr_lanes));
            let beta = rz_new / rz;
            rz = rz_new;
            rr = rr_new;
            for (p, &z) in self.p.iter_mut().zip(&self.z) {
                *p = z + beta * *p;
            }
            self.last_iterations = it + 1;
        }
        self.at_budget = self.last_iterations == self.max_iterations && rr.sqrt() > goal;
        Ok(())
    }
}

/// Independent partial sums of a reduction: one chain of dependent additions per lane
/// instead of one over the whole vector, so the additions overlap.
const LANES: usize = 4;

fn sum(lanes: [f64; LANES]) -> f64 {
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// A square sparse matrix in compressed-row form.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Csr {
    /// Entries per row when every row has been padded to the same length, else 0.
    width: usize,
    /// Row offsets (`m + 1`).
    row_start: Vec<u32>,
    /// Column of each entry.
    cols: Vec<u32>,
    /// Values.
    values: Vec<f64>,
}

impl Csr {
    /// `y = A x`; returns `xᵀ y`.
    fn product(&self, x: &[f64], y: &mut [f64]) -> f64 {
        match self.width {
            4 => self.product_fixed::<4>(x, y),
            5 => self.product_fixed::<5>(x, y),
            6 => self.product_fixed::<6>(x, y),
            7 => self.product_fixed::<7>(x, y),
            8 => self.product_fixed::<8>(x, y),
            9 => self.product_fixed::<9>(x, y),
            _ => self.product_general(x, y),
        }
    }

    fn product_general(&self, x: &[f64], y: &mut [f64]) -> f64 {
        let mut xy = [0.0; LANES];
        let rs = &self.row_start[..y.len() + 1];
        for_lanes!(y.len(), |k, lane| {
            let (s, e) = (rs[k] as usize, rs[k + 1] as usize);
            let mut acc = 0.0;
            for (&v, &c) in self.values[s..e].iter().zip(&self.cols[s..e]) {
                acc += v * x[c as usize];
            }
            y[k] = acc;
            xy[lane] += x[k] * acc;
        });
        sum(xy)
    }

    /// Rows of exactly `W` entries: the inner loop is unrolled, with two partial sums.
    fn product_fixed<const W: usize>(&self, x: &[f64], y: &mut [f64]) -> f64 {
        let m = y.len();
        let (values, cols) = (&self.values[..m * W], &self.cols[..m * W]);
        let mut xy = [0.0; LANES];
        for_lanes!(m, |k, lane| {
            let (v, c) = (&values[k * W..][..W], &cols[k * W..][..W]);
            let (mut even, mut odd) = (0.0, 0.0);
            for j in 0..W {
                let t = v[j] * x[c[j] as usize];
                if j % 2 == 0 {
                    even += t;
                } else {
                    odd += t;
                }
            }
            let acc = even + odd;
            y[k] = acc;
            xy[lane] += x[k] * acc;
        });
        sum(xy)
    }
}
