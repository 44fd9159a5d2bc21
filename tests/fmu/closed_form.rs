//! The mass-spring-damper FMU against the closed-form solution of the underdamped
//! oscillator: with F held constant, x − F/k decays as a damped cosine. [`check`] is
//! shared with the FMI 3.0 form of the same model (`fmi3.rs`).

use crate::fmus::{load, real, start, vr};

/// x(t) of m x'' + c x' + k x = F for x(0) = x0, x'(0) = v0 (underdamped) [m].
fn closed_form(t: f64, m: f64, k: f64, c: f64, x0: f64, v0: f64, f: f64) -> f64 {
    let omega = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    assert!(zeta < 1.0, "the reference is the underdamped solution");
    let omega_d = omega * (1.0 - zeta * zeta).sqrt();
    let eq = f / k;
    let y0 = x0 - eq;
    let decay = (-zeta * omega * t).exp();
    eq + decay
        * (y0 * (omega_d * t).cos() + (v0 + zeta * omega * y0) / omega_d * (omega_d * t).sin())
}

/// Steps the test FMU `stem` (msd or msd3) with h = 1 ms for 5 s under the constant
/// force `f` and compares x, and a with its definition, at every communication point.
/// Returns the largest |x − closed form| [m].
pub fn check(stem: &str, f: f64) -> f64 {
    let (m, k, c, x0, v0) = (1.5, 4.0, 0.4, 1.0, 0.5);
    let fmu = load(stem, "plant");
    let mut inst = start(
        &fmu,
        "plant",
        &[("m", m), ("k", k), ("c", c), ("x0", x0), ("v0", v0)],
    );
    let (x, v, a) = (vr(&fmu, "x"), vr(&fmu, "v"), vr(&fmu, "a"));
    inst.set_real(&[vr(&fmu, "F")], &[f]).expect("set F");
    assert_eq!(real(&inst, x), x0, "x at t = 0 is x0");
    let h = 1e-3;
    let mut worst = 0.0f64;
    for i in 0..5000 {
        let t = i as f64 * h;
        inst.do_step(t, h)
            .unwrap_or_else(|e| panic!("step {i}: {e}"));
        let t1 = (i + 1) as f64 * h;
        let want = closed_form(t1, m, k, c, x0, v0, f);
        let got = real(&inst, x);
        worst = worst.max((got - want).abs());
        assert!(
            (got - want).abs() <= 1e-9,
            "step {i} (t = {t1} s): x = {got}, closed form {want}"
        );
        let acc = (f - k * got - c * real(&inst, v)) / m;
        assert!(
            (real(&inst, a) - acc).abs() <= 1e-12,
            "step {i}: a is not (F - kx - cv)/m"
        );
    }
    // The run must actually move: 5 s is over 1.5 periods of the 2π/ω ≈ 3.8 s oscillation.
    let end = real(&inst, x);
    assert!((end - x0).abs() > 0.1, "x barely moved: {end}");
    eprintln!("{stem}, F = {f} N: worst |x - closed form| = {worst:e} m");
    worst
}

#[test]
fn msd_free_response_matches_the_closed_form() {
    check("msd", 0.0);
}

#[test]
fn msd_under_a_constant_force_settles_about_f_over_k() {
    check("msd", 2.0);
}
