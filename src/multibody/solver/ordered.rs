//! The exact solve of systems too large for the dense path: faer's sparse Cholesky,
//! ordered by approximate minimum degree (AMD), its symbolic analysis done once per
//! topology and its numeric factorization every solve into buffers kept between solves.
//!
//! Why faer: factorized in link order, `J M⁻¹ Jᵀ` fills in its whole profile (bandwidth
//! about twice the grid's width), which made the exact path 58–76× slower per step than
//! CG 10 on a 64×64 grid and would need ~131 GB on a 1000×1000 grid; an AMD order keeps
//! the factor close to the matrix's own sparsity. faer is the maintained Rust sparse
//! Cholesky with AMD and a supernodal factorization; writing an ordering and a
//! supernodal factorization here would be a library of its own.
//!
//! Simplicial below [`SUPERNODAL_MIN_LINKS`], supernodal from there: faer picks one by a
//! flop-count heuristic, which chose simplicial on a 64×64 grid, where supernodal was
//! 1.2–1.3× faster (`dsmcosim run` of 300 steps: 1.13 s against 1.35–1.46 s). On the
//! tight scene's settings for 1 s (RK4, two runs each): 16×16 (480 links) 0.37–0.39 s
//! simplicial against 0.49 s supernodal, 32×32 (1984 links) 2.40–2.48 s against
//! 2.38–2.39 s. A threshold on the size also keeps a run's arithmetic from depending on
//! a heuristic's flop estimate.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// The ordered factorization of one pattern, with its scratch memory.
pub(super) struct Ordered {
    /// The analysis, shared by the clones of a solver (it depends on the pattern only).
    symbolic: Arc<SymbolicCholesky<usize>>,
    l_values: Vec<f64>,
    factor_scratch: MemBuffer,
    solve_scratch: MemBuffer,
}

impl std::fmt::Debug for Ordered {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ordered")
            .field("factor_values", &self.l_values.len())
            .finish()
    }
}

/// An ordered factorization held by a solver. A clone (a fork of the world) shares the
/// analysis and gets buffers of its own, holding a copy of the factor (a solver that
/// reuses its factor continues from it); a solver restored from a checkpoint starts
/// empty and analyses the pattern again on its first solve: the same AMD order, so the
/// same bits.
#[derive(Debug, Default)]
pub(super) struct Slot(pub(super) Option<Ordered>);

impl Clone for Slot {
    fn clone(&self) -> Slot {
        Slot(self.0.as_ref().and_then(|o| {
            let mut copy = Ordered::with(Arc::clone(&o.symbolic))?;
            // A solver that reuses its factor must fork with it.
            copy.l_values.copy_from_slice(&o.l_values);
            Some(copy)
        }))
    }
}

/// Which layout a factor takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Layout {
    /// Simplicial below [`SUPERNODAL_MIN_LINKS`], supernodal from there: the faster
    /// factorization.
    BySize,
    /// Always simplicial: the faster triangular solves with one right-hand side, for a
    /// factor that is applied many times per factorization.
    Simplicial,
}

/// Systems of at least this many links are factorized supernodally, smaller ones
/// simplicially (see the module's documentation for the measurements).
pub(super) const SUPERNODAL_MIN_LINKS: usize = 1000;

/// The symbolic analysis of the lower triangle `(col_ptr, row_idx)` (sorted rows) of an
/// `n × n` symmetric pattern: AMD order, then the simplicial or supernodal structure.
fn analyse(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    layout: Layout,
) -> Option<SymbolicCholesky<usize>> {
    #[cfg(test)]
    ANALYSES.with(|c| c.set(c.get() + 1));
    let a = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
    let params = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: if layout == Layout::BySize && n >= SUPERNODAL_MIN_LINKS {
            SupernodalThreshold::FORCE_SUPERNODAL
        } else {
            SupernodalThreshold::FORCE_SIMPLICIAL
        },
        ..Default::default()
    };
    factorize_symbolic_cholesky(a, Side::Lower, Default::default(), params).ok()
}

/// Entries of the factor of the lower triangle `(col_ptr, row_idx)` of an `n × n`
/// pattern; `None` if faer refuses the pattern. The analysis is kept for the solver
/// that will factorize this very pattern ([`ANALYSED`]).
pub(super) fn factor_entries(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    layout: Layout,
) -> Option<u64> {
    let symbolic = analyse(n, col_ptr, row_idx, layout)?;
    let entries = symbolic.len_val() as u64;
    if let Ok(mut kept) = ANALYSED.lock() {
        *kept = Some((pattern_key(n, col_ptr, row_idx, layout), Arc::new(symbolic)));
    }
    Some(entries)
}

#[cfg(test)]
thread_local! {
    /// Analyses made on this thread (tests count them).
    pub(super) static ANALYSES: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// The last analysis [`factor_entries`] made, by the key of its pattern: a run's
/// budget estimate analyses the scene's pattern to bound its factor, and the run's
/// solver then takes that analysis instead of doing it again (4 s and a second AMD's
/// workspace on a million-body grid). One entry, taken by the first solver of the same
/// pattern; the analysis depends on the pattern only, so whoever takes it gets the same
/// bits it would have computed.
static ANALYSED: std::sync::Mutex<Option<(blake3::Hash, Arc<SymbolicCholesky<usize>>)>> =
    std::sync::Mutex::new(None);

/// What identifies an analysis: the pattern's size, columns and rows, and the layout.
fn pattern_key(n: usize, col_ptr: &[usize], row_idx: &[usize], layout: Layout) -> blake3::Hash {
    let mut h = blake3::Hasher::new();
    h.update(&(n as u64).to_le_bytes());
    h.update(&[u8::from(layout == Layout::Simplicial)]);
    for &x in col_ptr.iter().chain(row_idx) {
        h.update(&(x as u64).to_le_bytes());
    }
    h.finalize()
}

/// The analysis of this pattern if [`factor_entries`] kept it, taken out of the cache.
fn take_analysed(key: blake3::Hash) -> Option<Arc<SymbolicCholesky<usize>>> {
    let mut kept = ANALYSED.lock().ok()?;
    match kept.take() {
        Some((k, s)) if k == key => Some(s),
        other => {
            *kept = other;
            None
        }
    }
}

impl Ordered {
    /// The symbolic analysis of the lower triangle `(col_ptr, row_idx)` (sorted rows) of
    /// an `n × n` symmetric pattern, with its buffers; `None` if they cannot be allocated
    /// (faer's out-of-memory or index overflow, or the factor's own values).
    pub(super) fn new(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        layout: Layout,
    ) -> Option<Ordered> {
        let symbolic = match take_analysed(pattern_key(n, col_ptr, row_idx, layout)) {
            Some(symbolic) => symbolic,
            None => Arc::new(analyse(n, col_ptr, row_idx, layout)?),
        };
        Ordered::with(symbolic)
    }

    /// The factorization of an analysed pattern, with buffers of its own.
    fn with(symbolic: Arc<SymbolicCholesky<usize>>) -> Option<Ordered> {
        let factor_scratch = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        )
        .ok()?;
        let solve_scratch =
            MemBuffer::try_new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq)).ok()?;
        // Fallible: a factor too large for the memory left is an out-of-memory error of
        // the run (`SolveError::OutOfMemory`), not an abort.
        let mut l_values = Vec::new();
        l_values.try_reserve_exact(symbolic.len_val()).ok()?;
        l_values.resize(symbolic.len_val(), 0.0);
        Some(Ordered {
            l_values,
            symbolic,
            factor_scratch,
            solve_scratch,
        })
    }

    /// Factorizes the matrix with these `values` (in the pattern's order) and solves
    /// `A x = b`. `false` if `A` is not numerically positive definite: a pivot of the
    /// factorization (before its square root) at or below `min_pivot`, or a non-finite
    /// solution.
    pub(super) fn solve(
        &mut self,
        (n, col_ptr, row_idx): (usize, &[usize], &[usize]),
        values: &[f64],
        min_pivot: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> bool {
        if !self.factorize((n, col_ptr, row_idx), values, min_pivot) {
            return false;
        }
        x.copy_from_slice(b);
        self.apply_inverse(x);
        x.iter().all(|v| v.is_finite())
    }

    /// Factorizes the matrix with these `values` into the stored factor. `false` if
    /// `A` is not a mechanism's (a non-finite value, or faer finds a clearly negative
    /// pivot).
    ///
    /// A pivot (before its square root) at or below `min_pivot` is a row that depends
    /// on the rows eliminated before it (a redundant constraint, or a mechanism at a
    /// singular position): the factorization is redone with faer's dynamic
    /// regularization, which replaces each such pivot by `A`'s largest diagonal entry.
    /// The dependent row's column of the factor is then its round-off residual over a
    /// pivot of `A`'s own scale, so it leans on no later row and its multiplier is
    /// round-off: the dense path's dropped row (`solver::cholesky_column`), to working
    /// precision. A matrix without such a pivot gets the plain factorization's bits.
    pub(super) fn factorize(
        &mut self,
        pattern: (usize, &[usize], &[usize]),
        values: &[f64],
        min_pivot: f64,
    ) -> bool {
        if self.factorize_with(pattern, values, min_pivot, None) {
            return true;
        }
        if !values.iter().all(|v| v.is_finite()) {
            return false;
        }
        let (n, col_ptr, _) = pattern;
        // The diagonal entry is each column's first.
        let max_diag = col_ptr[..n].iter().map(|&i| values[i]).fold(0.0, f64::max);
        self.factorize_with(pattern, values, 0.0, Some((min_pivot, max_diag)))
    }

    /// One numeric factorization; `drop` = `(threshold, replacement)` regularizes the
    /// pivots at or below the threshold.
    fn factorize_with(
        &mut self,
        (n, col_ptr, row_idx): (usize, &[usize], &[usize]),
        values: &[f64],
        min_pivot: f64,
        drop: Option<(f64, f64)>,
    ) -> bool {
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx),
            values,
        );
        let (epsilon, delta) = drop.unwrap_or((0.0, 0.0));
        let regularization = LltRegularization {
            dynamic_regularization_delta: delta,
            dynamic_regularization_epsilon: epsilon,
        };
        let factored = self
            .symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Lower,
                regularization,
                Par::Seq,
                MemStack::new(&mut self.factor_scratch),
                Default::default(),
            )
            .is_ok();
        factored && self.min_pivot_squared() > min_pivot
    }

    /// `x ← (L Lᵀ)⁻¹ x` with the stored factor (of the last [`factorize`](Self::factorize)).
    pub(super) fn apply_inverse(&mut self, x: &mut [f64]) {
        let n = x.len();
        let llt = LltRef::new(&self.symbolic, &self.l_values);
        let rhs = MatMut::from_column_major_slice_mut(x, n, 1);
        llt.solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.solve_scratch),
        );
    }

    /// The smallest squared diagonal entry of the factor `L` (the pivots of the
    /// elimination): faer reports only a non-positive pivot, while a pivot that is
    /// round-off relative to `A`'s diagonal means `A` is singular to working precision.
    fn min_pivot_squared(&self) -> f64 {
        let s = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                // Each column's diagonal entry is its first.
                let cols = &s.col_ptr()[..s.ncols()];
                return cols
                    .iter()
                    .map(|&i| self.l_values[i] * self.l_values[i])
                    .fold(f64::INFINITY, f64::min);
            }
            SymbolicCholeskyRaw::Supernodal(s) => s,
        };
        let (begin, end) = (s.supernode_begin(), s.supernode_end());
        let (rows_ptr, vals_ptr) = (s.col_ptr_for_row_idx(), s.col_ptr_for_val());
        let mut min = f64::INFINITY;
        for sn in 0..s.n_supernodes() {
            // A supernode's values are one column-major block: its columns' diagonal
            // block on top of the rows below it.
            let cols = end[sn] - begin[sn];
            let rows = cols + rows_ptr[sn + 1] - rows_ptr[sn];
            for c in 0..cols {
                let l = self.l_values[vals_ptr[sn] + c * rows + c];
                min = min.min(l * l);
            }
        }
        min
    }
}
