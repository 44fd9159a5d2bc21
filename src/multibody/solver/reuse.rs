//! The exact path with its factorization reused: between two factorizations of `A`, a
//! solve runs the conjugate gradient preconditioned by the last factor `L Lᵀ` (of `A`
//! a few solves ago), warm-started from the previous solution, to a relative residual.
//!
//! Why: on a large grid the sparse factorization is most of a step (60 % of a tight
//! 64×64 RK4 step's profile), while `A` moves little from one solve to the next (the
//! links turn by `ω dt` per step). Preconditioned by a factor of a nearby `A`, CG
//! sees a matrix close to the identity and converges in a few iterations, each one
//! product with the assembled `A` and one pair of triangular solves with the stored
//! factor. A solve that does not reach its tolerance within its iterations
//! factorizes `A` afresh and solves exactly, so every solution is within the
//! tolerance: the reuse trades the factorization's cost for at most that residual,
//! never for a stalled solve.
//!
//! Deterministic: when to factorize depends only on the count of solves since the last
//! factorization and on the iterations' arithmetic, and a checkpoint keeps the count
//! and the values of `A` that were factorized (a restored run factorizes them again,
//! the same bits as the factor it lost).

use super::ordered::Ordered;

/// The reuse policy and its state.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct Reuse {
    /// Solves per factorization: the first of every `every` solves factorizes.
    every: usize,
    /// Relative residual `‖b − A x‖₂ / ‖b‖₂` a preconditioned solve stops at.
    tolerance: f64,
    /// Preconditioned iterations before a solve gives up and factorizes.
    max_iterations: usize,
    /// Solves since the last factorization (0: none yet, or due).
    since: usize,
    /// The values of `A` (lower triangle, the pattern's order) that were factorized.
    factored: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    /// Iterations of the last solve (0 when it factorized).
    last_iterations: usize,
    /// Factorizations so far (the ones a failed preconditioned solve forced included).
    factorizations: u64,
}

/// What the exact solve does next with this system.
pub(super) enum Plan {
    /// Factorize `A` and solve with the new factor.
    Factorize,
    /// Solve iteratively with the stored factor.
    Iterate,
}

impl Reuse {
    /// A policy for a system of `m` links.
    pub(super) fn new(every: usize, tolerance: f64, max_iterations: usize, m: usize) -> Reuse {
        Reuse {
            every,
            tolerance,
            max_iterations,
            since: 0,
            factored: Vec::new(),
            r: vec![0.0; m],
            z: vec![0.0; m],
            p: vec![0.0; m],
            ap: vec![0.0; m],
            last_iterations: 0,
            factorizations: 0,
        }
    }

    /// Whether this solve factorizes (the count says so, or there is no factor yet).
    pub(super) fn plan(&self) -> Plan {
        if self.since == 0 || self.since >= self.every {
            Plan::Factorize
        } else {
            Plan::Iterate
        }
    }

    /// The values a restored solver must factorize to recover the factor it lost, when
    /// it has one in use.
    pub(super) fn lost_factor(&self) -> Option<&[f64]> {
        (self.since > 0 && self.since < self.every && !self.factored.is_empty())
            .then_some(&self.factored[..])
    }

    /// Records a factorization of `values` (this solve's `A`).
    pub(super) fn factorized(&mut self, values: &[f64]) {
        self.factored.clear();
        self.factored.extend_from_slice(values);
        self.since = 1;
        self.last_iterations = 0;
        self.factorizations += 1;
    }

    /// Iterations of the last solve.
    pub(super) fn last_iterations(&self) -> usize {
        self.last_iterations
    }

    /// Factorizations so far.
    pub(super) fn factorizations(&self) -> u64 {
        self.factorizations
    }

    /// Solves `A x = b` (`A`: the lower triangle `values` on `(col_ptr, row_idx)`) by
    /// CG preconditioned with `factor`, from the warm start in `x`. `true` when the
    /// relative residual reached the tolerance within the iteration budget (then `x`
    /// is the solution); `false` leaves `x` unspecified and the caller factorizes.
    pub(super) fn iterate(
        &mut self,
        factor: &mut Ordered,
        (col_ptr, row_idx, values): (&[usize], &[usize], &[f64]),
        b: &[f64],
        x: &mut [f64],
    ) -> bool {
        let norm_b = dot(b, b).sqrt();
        if norm_b == 0.0 {
            // `A` is positive definite: the solution is zero (a scene at rest), which no
            // relative residual could confirm.
            x.fill(0.0);
            self.since += 1;
            self.last_iterations = 0;
            return true;
        }
        let goal = self.tolerance * norm_b;
        symmetric_product(col_ptr, row_idx, values, x, &mut self.ap);
        for ((r, &b), &ax) in self.r.iter_mut().zip(b).zip(&self.ap) {
            *r = b - ax;
        }
        let mut iterations = 0;
        let mut converged = dot(&self.r, &self.r).sqrt() <= goal;
        if !converged {
            self.z.copy_from_slice(&self.r);
            factor.apply_inverse(&mut self.z);
            self.p.copy_from_slice(&self.z);
            let mut rz = dot(&self.r, &self.z);
            while iterations < self.max_iterations {
                iterations += 1;
                symmetric_product(col_ptr, row_idx, values, &self.p, &mut self.ap);
                let pap = dot(&self.p, &self.ap);
                // A non-positive curvature (round-off on a singular `A`) or a NaN ends
                // the iteration; the caller then factorizes, which reports it.
                if pap.is_nan() || pap <= 0.0 || !rz.is_finite() {
                    break;
                }
                let alpha = rz / pap;
                for ((x, r), (&p, &ap)) in x
                    .iter_mut()
                    .zip(self.r.iter_mut())
                    .zip(self.p.iter().zip(&self.ap))
                {
                    *x += alpha * p;
                    *r -= alpha * ap;
                }
                if dot(&self.r, &self.r).sqrt() <= goal {
                    converged = true;
                    break;
                }
                self.z.copy_from_slice(&self.r);
                factor.apply_inverse(&mut self.z);
                let rz_next = dot(&self.r, &self.z);
                let beta = rz_next / rz;
                rz = rz_next;
                for (p, &z) in self.p.iter_mut().zip(&self.z) {
                    *p = z + beta * *p;
                }
            }
        }
        if converged && x.iter().all(|v| v.is_finite()) {
            self.since += 1;
            self.last_iterations = iterations;
            true
        } else {
            false
        }
    }
}

/// `y = A x` for symmetric `A` stored as its lower triangle in compressed-column form
/// (each column's diagonal entry first).
fn symmetric_product(
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
    x: &[f64],
    y: &mut [f64],
) {
    y.fill(0.0);
    for (j, &xj) in x.iter().enumerate() {
        let (start, end) = (col_ptr[j], col_ptr[j + 1]);
        let mut yj = values[start] * xj;
        for (&i, &v) in row_idx[start + 1..end].iter().zip(&values[start + 1..end]) {
            y[i] += v * xj;
            yj += v * x[i];
        }
        y[j] += yj;
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}
