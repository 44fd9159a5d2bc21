//! The feasible set of the delay optimizers (a box and a budget on the inverses) and
//! their errors.

use super::simplex::regular_simplex;

/// Errors of [`super::Dsm::new`], [`Feasible`] and the Nelder–Mead baseline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimplexError {
    /// The start point has no coordinates.
    #[error("the start point has no coordinates")]
    Empty,
    /// Two vectors that must have the same length do not.
    #[error("{what} has {got} coordinates, expected {expected}")]
    Dimension {
        /// Which vector is too long or too short.
        what: &'static str,
        /// The length it should have.
        expected: usize,
        /// The length it has.
        got: usize,
    },
    /// A start coordinate is NaN or infinite.
    #[error("start point coordinate {index} is not finite: {value}")]
    NonFiniteStart {
        /// 0-based coordinate.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The simplex size is not finite and positive.
    #[error("simplex size must be finite and positive, got {0}")]
    BadSize(f64),
    /// `m_r = 0`.
    #[error("reflections per iteration must be at least 1, got 0")]
    NoReflections,
    /// A bound pair is NaN or has `lower > upper` (or `lower = +∞`, `upper = −∞`).
    #[error("bounds of coordinate {index} are not an interval: [{lower}, {upper}]")]
    BadBounds {
        /// 0-based coordinate.
        index: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A budget weight `k_i` is negative or not finite.
    #[error("budget weight {index} must be finite and non-negative, got {value}")]
    BadWeight {
        /// 0-based coordinate.
        index: usize,
        /// The offending weight.
        value: f64,
    },
    /// The budget `B` is not finite.
    #[error("budget must be finite, got {0}")]
    BadBudget(f64),
    /// A budget was given but a coordinate it weighs has an infinite bound.
    #[error("a budget needs finite bounds; coordinate {index} has [{lower}, {upper}]")]
    UnboundedBudget {
        /// 0-based coordinate.
        index: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// The box is narrower than the simplex in one coordinate.
    #[error("coordinate {index}: box width {width} is smaller than the simplex extent {extent}")]
    BoxTooNarrow {
        /// 0-based coordinate.
        index: usize,
        /// `upper − lower`.
        width: f64,
        /// Extent of the simplex along that coordinate.
        extent: f64,
    },
    /// No placement of the simplex inside the box satisfies the budget.
    #[error("no placement of a simplex of size {size} inside the box meets the budget {budget}")]
    BudgetUnreachable {
        /// Edge length of the simplex.
        size: f64,
        /// The budget `B`.
        budget: f64,
    },
    /// A convergence tolerance is negative or NaN.
    #[error("tolerance must be non-negative, got {0}")]
    BadTolerance(f64),
}

/// The error of [`super::Dsm::new`] (the same type serves both optimizers).
pub type DsmError = SimplexError;

/// The feasible set: a box `lower ≤ x ≤ upper` and optionally a linear budget on the
/// inverses, `Σ k_i / x_i ≤ B` (method §5, CP: `k_i` weights [1], `B` [Hz] when `x`
/// are delays [s]).
///
/// Stored as data so that the optimizers stay `Clone`. Bounds may be infinite when no
/// budget is given. Every coordinate with `k_i > 0` must be positive to meet the budget.
/// The set is convex (`k_i / x_i` is convex for `x_i > 0`), which the Nelder–Mead
/// contractions rely on. Mapping the method’s CP (§5) (last delay eliminated through the budget)
/// onto the controlled coordinates is the caller's business.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Feasible {
    lower: Vec<f64>,
    upper: Vec<f64>,
    budget: Option<(Vec<f64>, f64)>,
}

impl Feasible {
    /// All of `R^n`.
    pub fn unbounded(n: usize) -> Feasible {
        Feasible {
            lower: vec![f64::NEG_INFINITY; n],
            upper: vec![f64::INFINITY; n],
            budget: None,
        }
    }

    /// The box `lower ≤ x ≤ upper` (infinite bounds allowed).
    pub fn boxed(lower: Vec<f64>, upper: Vec<f64>) -> Result<Feasible, SimplexError> {
        if lower.len() != upper.len() {
            return Err(SimplexError::Dimension {
                what: "upper bound",
                expected: lower.len(),
                got: upper.len(),
            });
        }
        for (index, (&l, &u)) in lower.iter().zip(&upper).enumerate() {
            if l.is_nan() || u.is_nan() || l > u || l == f64::INFINITY || u == f64::NEG_INFINITY {
                return Err(SimplexError::BadBounds {
                    index,
                    lower: l,
                    upper: u,
                });
            }
        }
        Ok(Feasible {
            lower,
            upper,
            budget: None,
        })
    }

    /// Adds the budget `Σ k_i / x_i ≤ b` (weights `k_i ≥ 0`; bounds of weighted coordinates
    /// must be finite).
    pub fn with_budget(mut self, k: Vec<f64>, b: f64) -> Result<Feasible, SimplexError> {
        if k.len() != self.lower.len() {
            return Err(SimplexError::Dimension {
                what: "budget weights",
                expected: self.lower.len(),
                got: k.len(),
            });
        }
        for (index, &value) in k.iter().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(SimplexError::BadWeight { index, value });
            }
            let (lower, upper) = (self.lower[index], self.upper[index]);
            if value > 0.0 && !(lower.is_finite() && upper.is_finite()) {
                return Err(SimplexError::UnboundedBudget {
                    index,
                    lower,
                    upper,
                });
            }
        }
        if !b.is_finite() {
            return Err(SimplexError::BadBudget(b));
        }
        self.budget = Some((k, b));
        Ok(self)
    }

    /// Number of coordinates.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    /// Lower bounds.
    pub fn lower(&self) -> &[f64] {
        &self.lower
    }

    /// Upper bounds.
    pub fn upper(&self) -> &[f64] {
        &self.upper
    }

    /// The budget `(k, B)`, if any.
    pub fn budget(&self) -> Option<(&[f64], f64)> {
        self.budget.as_ref().map(|(k, b)| (k.as_slice(), *b))
    }

    /// Whether `x` is finite, of the right length, inside the box and within the budget.
    pub fn contains(&self, x: &[f64]) -> bool {
        if x.len() != self.dim() || x.iter().any(|v| !v.is_finite()) {
            return false;
        }
        let in_box = x
            .iter()
            .zip(self.lower.iter().zip(&self.upper))
            .all(|(v, (l, u))| l <= v && v <= u);
        in_box && self.within_budget(x)
    }

    fn within_budget(&self, x: &[f64]) -> bool {
        match &self.budget {
            None => true,
            Some((k, b)) => {
                let mut sum = 0.0;
                for (&k, &x) in k.iter().zip(x) {
                    if k > 0.0 {
                        if x <= 0.0 {
                            return false;
                        }
                        sum += k / x;
                    }
                }
                sum <= *b
            }
        }
    }

    /// The regular simplex of edge `edge` centred on `x0` ([`regular_simplex`]), moved
    /// into the feasible set if it is not inside.
    ///
    /// The move is deterministic and keeps the shape: first the centre is projected onto
    /// the box of centres whose simplex fits the bounds (per coordinate, the least move);
    /// if the budget is still violated, the centre slides along the segment to the upper
    /// corner of that box — the most budget-friendly placement, since `Σ k_i / x_i` falls
    /// as any coordinate grows — and bisection finds the first point of the segment where
    /// all vertices meet the budget. Vertex coordinates are clamped into the box to undo
    /// rounding of `centre + offset` (a change of at most a few ulp).
    pub fn fit_simplex(&self, x0: &[f64], edge: f64) -> Result<Vec<Vec<f64>>, SimplexError> {
        let n = x0.len();
        if n == 0 {
            return Err(SimplexError::Empty);
        }
        if n != self.dim() {
            return Err(SimplexError::Dimension {
                what: "start point",
                expected: self.dim(),
                got: n,
            });
        }
        if let Some((index, &value)) = x0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SimplexError::NonFiniteStart { index, value });
        }
        if !(edge.is_finite() && edge > 0.0) {
            return Err(SimplexError::BadSize(edge));
        }
        // Offsets of the vertices from the centre.
        let offsets = regular_simplex(&vec![0.0; n], edge);
        let mut centre = x0.to_vec();
        let mut top = vec![0.0; n];
        for d in 0..n {
            let lo_off = offsets.iter().map(|o| o[d]).fold(f64::INFINITY, f64::min);
            let hi_off = offsets
                .iter()
                .map(|o| o[d])
                .fold(f64::NEG_INFINITY, f64::max);
            let (lo, hi) = (self.lower[d] - lo_off, self.upper[d] - hi_off);
            if lo > hi {
                return Err(SimplexError::BoxTooNarrow {
                    index: d,
                    width: self.upper[d] - self.lower[d],
                    extent: hi_off - lo_off,
                });
            }
            centre[d] = centre[d].clamp(lo, hi);
            top[d] = hi;
        }
        let place = |c: &[f64]| -> Vec<Vec<f64>> {
            offsets
                .iter()
                .map(|o| {
                    (0..n)
                        .map(|d| (c[d] + o[d]).clamp(self.lower[d], self.upper[d]))
                        .collect()
                })
                .collect()
        };
        let fits = |vs: &[Vec<f64>]| vs.iter().all(|v| self.contains(v));
        let vertices = place(&centre);
        if fits(&vertices) {
            return Ok(vertices);
        }
        // Only the budget can fail now. Coordinates with an infinite upper bound carry no
        // weight (checked in `with_budget`), so they stay where they are.
        for d in 0..n {
            if !top[d].is_finite() {
                top[d] = centre[d];
            }
        }
        let along = |s: f64| -> Vec<f64> {
            (0..n)
                .map(|d| centre[d] + s * (top[d] - centre[d]))
                .collect()
        };
        if !fits(&place(&top)) {
            return Err(SimplexError::BudgetUnreachable {
                size: edge,
                budget: self.budget.as_ref().map_or(f64::NAN, |(_, b)| *b),
            });
        }
        let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if fits(&place(&along(mid))) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Ok(place(&along(hi)))
    }
}
