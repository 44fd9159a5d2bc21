//! Paired comparisons of two methods over the same measurement windows (method §5).
//!
//! The cost of a window changes up to 2× from window to window with the load and the
//! chaotic motion, while across delays it changes by about 10 %. A mean over one
//! method's windows set against a mean over another's (a baseline is `NaN` in a window
//! where its choice was infeasible) then compares the windows as much as the methods.
//! Every comparison here is over the windows where both were measured: per window the
//! difference `a − b`; the windows `a` won and lost, with the two-sided exact sign test
//! (ties left out), which gives the verdict; and beside it the mean difference with its
//! 95 % confidence interval (paired t), a secondary reading of the size of the effect.

use statrs::distribution::{ContinuousCDF, StudentsT};

/// Method `a` against method `b` over the windows where both have a finite objective
/// (lower is better).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Paired {
    /// Windows where both were measured.
    pub n: usize,
    /// Windows left out: either method infeasible there, diverged or not measured.
    pub excluded: usize,
    /// Windows where `a` is lower.
    pub wins: usize,
    /// Windows where `a` is higher.
    pub losses: usize,
    /// Mean of `a` over the paired windows.
    pub mean_a: f64,
    /// Mean of `b` over the paired windows.
    pub mean_b: f64,
    /// `mean_a / mean_b`.
    pub ratio: f64,
    /// Mean of `a − b`.
    pub mean_difference: f64,
    /// 95 % confidence interval of the mean difference (paired t, `n − 1` degrees of
    /// freedom); `None` below 2 windows.
    pub ci95: Option<[f64; 2]>,
    /// Two-sided sign test of wins against losses (ties left out): the probability of
    /// a split at least this uneven if either method were as likely to win a window.
    pub sign_test_p: f64,
}

/// Level of the sign test behind [`Paired::verdict`]: two-sided, 5 %, for one
/// comparison on its own (a table of many comparisons corrects for their number itself,
/// as results/summarize_claims.py does with Holm–Bonferroni; method §5).
pub const SIGN_TEST_LEVEL: f64 = 0.05;

/// What a paired comparison says, by the sign test (method §5, the primary test).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The sign test's p is below [`SIGN_TEST_LEVEL`] and `a` won more windows.
    Better,
    /// The sign test's p is below [`SIGN_TEST_LEVEL`] and `a` lost more windows.
    Worse,
    /// The sign test's p is at or above [`SIGN_TEST_LEVEL`] (always so below 6 windows
    /// that are not ties).
    NotSignificant,
}

impl Paired {
    /// Compares `a` with `b` window by window (the two slices are per window, in the
    /// same order; a non-finite value leaves its window out).
    pub fn new(a: &[f64], b: &[f64]) -> Paired {
        assert_eq!(a.len(), b.len(), "one value per window for each method");
        let pairs: Vec<(f64, f64)> = a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(&x, &y)| (x, y))
            .collect();
        let n = pairs.len();
        let mean = |f: &dyn Fn(&(f64, f64)) -> f64| pairs.iter().map(f).sum::<f64>() / n as f64;
        let (mean_a, mean_b) = if n == 0 {
            (f64::NAN, f64::NAN)
        } else {
            (mean(&|p| p.0), mean(&|p| p.1))
        };
        let mean_difference = if n == 0 {
            f64::NAN
        } else {
            mean(&|p| p.0 - p.1)
        };
        let ci95 = (n >= 2).then(|| {
            let var = pairs
                .iter()
                .map(|p| (p.0 - p.1 - mean_difference).powi(2))
                .sum::<f64>()
                / (n - 1) as f64;
            let t = StudentsT::new(0.0, 1.0, (n - 1) as f64)
                .expect("ok: n − 1 ≥ 1 degrees of freedom")
                .inverse_cdf(0.975);
            let half = t * (var / n as f64).sqrt();
            [mean_difference - half, mean_difference + half]
        });
        let wins = pairs.iter().filter(|p| p.0 < p.1).count();
        let losses = pairs.iter().filter(|p| p.0 > p.1).count();
        Paired {
            n,
            excluded: a.len() - n,
            wins,
            losses,
            mean_a,
            mean_b,
            ratio: mean_a / mean_b,
            mean_difference,
            ci95,
            sign_test_p: sign_test(wins, losses),
        }
    }

    /// Better, worse or not significantly different by the two-sided exact sign test at
    /// [`SIGN_TEST_LEVEL`], uncorrected: this comparison taken alone. The t interval
    /// (`ci95`) is shown beside it and does not enter the verdict.
    pub fn verdict(&self) -> Verdict {
        if self.sign_test_p >= SIGN_TEST_LEVEL || self.wins == self.losses {
            Verdict::NotSignificant
        } else if self.wins > self.losses {
            Verdict::Better
        } else {
            Verdict::Worse
        }
    }
}

/// Two-sided exact sign test: `P(min(W, L) ≤ min(w, l))` doubled (at most 1) for
/// `W + L = w + l` fair coin flips. Written out here (a binomial tail summed in log
/// space, so thousands of windows neither overflow nor lose the small tail) since it is
/// a few lines.
fn sign_test(wins: usize, losses: usize) -> f64 {
    let n = wins + losses;
    let mut ln_term = -(n as f64) * std::f64::consts::LN_2; // ln(C(n, 0) / 2^n)
    let mut tail = 0.0;
    for i in 0..=wins.min(losses) {
        tail += ln_term.exp();
        ln_term += ((n - i) as f64).ln() - ((i + 1) as f64).ln();
    }
    (2.0 * tail).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_window_either_method_missed_leaves_the_pair_and_is_counted() {
        let p = Paired::new(&[1.0, 2.0, f64::NAN, 4.0], &[2.0, f64::NAN, 1.0, 5.0]);
        assert_eq!((p.n, p.excluded, p.wins, p.losses), (2, 2, 2, 0));
        assert_eq!((p.mean_a, p.mean_b), (2.5, 3.5));
        assert_eq!(p.mean_difference, -1.0);
    }

    #[test]
    fn the_interval_is_the_paired_t_interval() {
        // Differences −1, −2, −3: mean −2, s = 1, t(0.975, 2) = 4.302653; half-width
        // 4.302653 / √3 = 2.484138 (tables).
        let p = Paired::new(&[1.0, 1.0, 1.0], &[2.0, 3.0, 4.0]);
        let [lo, hi] = p.ci95.expect("3 windows");
        assert!((lo - (-2.0 - 2.484138)).abs() < 1e-5, "{lo}");
        assert!((hi - (-2.0 + 2.484138)).abs() < 1e-5, "{hi}");
    }

    #[test]
    fn the_verdict_is_the_sign_tests_not_the_intervals() {
        // Twenty windows each 1 lower: 20 of 20, p = 2^−19, better; and the other way.
        let a: Vec<f64> = (0..20).map(|i| 10.0 + 0.1 * (i % 3) as f64).collect();
        let b: Vec<f64> = a.iter().map(|x| x + 1.0).collect();
        assert_eq!(Paired::new(&a, &b).verdict(), Verdict::Better);
        assert_eq!(Paired::new(&b, &a).verdict(), Verdict::Worse);
        // 3 of 3 lower: the interval excludes zero, but p = 0.25: not significant.
        let p = Paired::new(&[1.0, 1.0, 1.0], &[2.0, 2.1, 2.2]);
        assert!(p.ci95.expect("3 windows")[1] < 0.0);
        assert_eq!(p.verdict(), Verdict::NotSignificant);
        // 15 windows won by 0.01, 5 lost by 1: the interval says worse (mean +0.2425),
        // the sign test (15 of 20, p = 0.041) says better.
        let a: Vec<f64> = (0..20).map(|i| if i < 15 { 0.99 } else { 2.0 }).collect();
        let p = Paired::new(&a, &[1.0; 20]);
        assert!(p.ci95.expect("20 windows")[0] > 0.0, "{:?}", p.ci95);
        assert!((p.sign_test_p - 0.041389).abs() < 1e-5, "{}", p.sign_test_p);
        assert_eq!(p.verdict(), Verdict::Better);
        // Ties leave the test: 6 of 6 won and 14 ties is p = 0.03125, better.
        let a: Vec<f64> = (0..20).map(|i| if i < 6 { 0.5 } else { 1.0 }).collect();
        let p = Paired::new(&a, &[1.0; 20]);
        assert_eq!((p.wins, p.losses, p.n), (6, 0, 20));
        assert_eq!(p.verdict(), Verdict::Better);
    }

    #[test]
    fn the_sign_test_matches_the_binomial_tail() {
        // 16 of 30: P(X ≤ 14) for X ~ B(30, 1/2) is 0.4278 (tables), doubled 0.8555.
        assert!(
            (sign_test(16, 14) - 0.855536).abs() < 1e-5,
            "{}",
            sign_test(16, 14)
        );
        // 12 of 16: 2 · P(X ≤ 4), X ~ B(16, 1/2) = 2 · 0.038406 = 0.076813.
        assert!(
            (sign_test(12, 4) - 0.076813).abs() < 1e-5,
            "{}",
            sign_test(12, 4)
        );
        assert_eq!(sign_test(5, 5), 1.0);
        assert_eq!(sign_test(0, 0), 1.0);
        // 3000 of 3000: far below any float's reach of 2^−3000, but not NaN.
        assert_eq!(sign_test(3000, 0), 0.0);
    }
}
