//! The DSM's simplex: the regular starting simplex, reflection and the ranking rules of
//! the module docs of [`super`], and the minimum size that can track a moving optimum.

use std::cmp::Ordering;

/// The regular simplex of `N + 1` vertices with every edge `edge`, centred (vertex mean)
/// on `centre` (`N = centre.len()`).
///
/// Construction: the points `u_0 = a·(1, …, 1)` with `a = (1 − √(N+1)) / N` and
/// `u_i = e_i` (unit vectors, `i = 1..N`) are pairwise `√2` apart; they are shifted by
/// their mean and scaled by `edge / √2`. Vertex 0 is the one on the diagonal. For `N = 1`
/// this gives `x0 − edge/2, x0 + edge/2`. Deterministic; `N = 0` gives the single point.
pub fn regular_simplex(centre: &[f64], edge: f64) -> Vec<Vec<f64>> {
    let n = centre.len();
    if n == 0 {
        return vec![Vec::new()];
    }
    let nf = n as f64;
    let a = (1.0 - (nf + 1.0).sqrt()) / nf;
    let mean = (a + 1.0) / (nf + 1.0);
    let scale = edge / std::f64::consts::SQRT_2;
    (0..=n)
        .map(|i| {
            (0..n)
                .map(|d| {
                    let u = if i == 0 {
                        a
                    } else if d + 1 == i {
                        1.0
                    } else {
                        0.0
                    };
                    centre[d] + scale * (u - mean)
                })
                .collect()
        })
        .collect()
}

/// The smallest simplex size that can follow an optimum moving at `speed` when every
/// measurement takes `period`: `D_smin = (m_r + 1) v T` (method §5; one iteration
/// takes `m_r + 1` measurements, so the optimum moves at most `D_smin` per iteration).
/// Units: `speed` [x/s], `period` [s], result [x].
pub fn d_s_min(reflections: usize, speed: f64, period: f64) -> f64 {
    (reflections as f64 + 1.0) * speed * period
}

/// A simplex with its stored costs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(super) struct Simplex {
    pub(super) x: Vec<Vec<f64>>,
    pub(super) cost: Vec<f64>,
    pub(super) infeasible: Vec<bool>,
}

impl Simplex {
    pub(super) fn unmeasured(x: Vec<Vec<f64>>) -> Simplex {
        let m = x.len();
        Simplex {
            x,
            cost: vec![f64::INFINITY; m],
            infeasible: vec![false; m],
        }
    }

    /// Orders vertices by `(infeasible, cost, index)`.
    pub(super) fn order(&self, a: usize, b: usize) -> Ordering {
        self.infeasible[a]
            .cmp(&self.infeasible[b])
            .then(self.cost[a].total_cmp(&self.cost[b]))
            .then(a.cmp(&b))
    }

    pub(super) fn best(&self) -> usize {
        (1..self.x.len()).fold(0, |best, i| {
            if self.order(i, best) == Ordering::Less {
                i
            } else {
                best
            }
        })
    }

    /// The worst vertex other than `skip`.
    pub(super) fn worst_except(&self, skip: Option<usize>) -> usize {
        let mut worst: Option<usize> = None;
        for i in (0..self.x.len()).filter(|&i| Some(i) != skip) {
            worst = match worst {
                Some(w) if self.order(i, w) != Ordering::Greater => Some(w),
                _ => Some(i),
            };
        }
        worst.unwrap_or(0)
    }

    /// `2 · centroid(others) − x_r`.
    pub(super) fn reflect(&self, r: usize) -> Vec<f64> {
        let others = (self.x.len() - 1) as f64;
        (0..self.x[r].len())
            .map(|d| {
                let sum: f64 = (0..self.x.len())
                    .filter(|&j| j != r)
                    .map(|j| self.x[j][d])
                    .sum();
                2.0 * sum / others - self.x[r][d]
            })
            .collect()
    }

    /// Whether `self` is a strictly better candidate than `other`.
    pub(super) fn beats(&self, other: &Simplex) -> bool {
        let (a, b) = (self.score(), other.score());
        a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)) == Ordering::Less
    }

    /// Candidate score: (infeasible vertices, mean cost of the others).
    pub(super) fn score(&self) -> (usize, f64) {
        let bad = self.infeasible.iter().filter(|&&b| b).count();
        let (sum, count) = self
            .cost
            .iter()
            .zip(&self.infeasible)
            .filter(|(_, &b)| !b)
            .fold((0.0, 0usize), |(s, c), (v, _)| (s + v, c + 1));
        let mean = if count == 0 {
            f64::INFINITY
        } else {
            sanitize(sum / count as f64)
        };
        (bad, mean)
    }
}

/// NaN is stored as `+∞`.
pub(crate) fn sanitize(cost: f64) -> f64 {
    if cost.is_nan() {
        f64::INFINITY
    } else {
        cost
    }
}
