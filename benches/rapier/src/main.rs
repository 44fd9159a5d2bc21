//! dsmcosim beside Rapier: the same N×N grids of linked bodies, stepped by both in one
//! process, compared in body-steps per second at matched max |w| (issue 17 item 3).
//!
//! Run (from the repository root):
//!
//! ```text
//! cargo run --release --manifest-path benches/rapier/Cargo.toml -- [--grids 16,32,64,128]
//!     [--classes loose,tight] [--steps N] [--joint distance|rope] [--substeps N]
//!     [--loose-substeps N] [--warmstart-joints] [--max-substeps N] [--tight-exact]
//! ```
//!
//! This crate is its own workspace (see its Cargo.toml), so the main crate's tests,
//! benches and CI never compile Rapier.
//!
//! **The scene.** Each case parses the scenario model
//! `{"grid": {"rows": N, "cols": N, "spacing": 1.8, "mass": 1, "size": 0.2}}` with the
//! 20 N sinusoidal corner load on body 1 (`amplitude [0, 0, 20]`, ω = 2 rad/s, no
//! gravity: dsmcosim's model has none) through `dsmcosim::scenario::parse_str`, and
//! builds *both* worlds from that one validated [`Scenario`]: Rapier gets the same
//! bodies (mass, principal inertia, position), the same links (body pair, anchors, rest
//! length) and the same force law, so the two cannot drift apart.
//!
//! **The accuracy classes.** dsmcosim at dt = 1 ms:
//! - `loose`: the thesis defaults (explicit Euler, SMC μ 50 ms, K 10 m/s, ε 0.1 m) with
//!   CG 10 (`{"kind": "cg", "max_iterations": 10, "tolerance": 0}`);
//! - `tight`: the settings of `scenarios/grid64_tight.json` (RK4, SMC μ 2 ms, K 200 m/s,
//!   ε 0.1 m, `cholesky_pcg`: the exact solve's factor reused for 20 solves, CG
//!   preconditioned by it to 1e-8 between), at every grid size; `--tight-exact` runs
//!   it on `cholesky` (a factorization every solve) instead.
//!
//! Rapier at the same dt: `loose` runs its default integration parameters (4 substeps,
//! 1 PGS iteration per substep); `tight` searches the fewest substeps
//! (`num_solver_iterations`) at which its max |w| is at or below dsmcosim's tight max |w|
//! on that grid ([`search_substeps`]), up to `--max-substeps` (if that is not enough, the
//! table shows the tightest run and its cost).
//! `--substeps N` skips the search; `--loose-substeps N` replaces Rapier's default 4
//! substeps in the loose rows. Every run that the search tried is printed on stderr;
//! the table times the last one.
//!
//! **The joint.** Rapier 0.36 has no two-sided distance joint. Its `RopeJoint` is a
//! `GenericJoint` whose linear axes are coupled (one row along the anchor-to-anchor
//! direction) with a limit `[0, max]`, and the coupled linear limit row is one-sided
//! whatever the limits (`limit_linear_coupled`: impulse in `[0, ∞)`, "FIXME: handle min
//! limit too"): with limits `[L, L]` it still only pulls, so a link can go slack
//! (`--joint rope` runs that, to show it). The two-sided row Rapier does build on coupled
//! linear axes is the coupled *motor* (`motor_linear_coupled`: impulse in `[-max, max]`,
//! right-hand side `(|d| − target)·erp/dt`). So `--joint distance` (the default) is a
//! `GenericJoint` with the linear axes coupled and a position motor on them, target = the
//! rest length L, unlimited force, and the stiffness and damping that give the motor the
//! softness Rapier gives every locked joint axis (`SpringCoefficients::joint_defaults`:
//! 1 MHz natural frequency, damping ratio 1; `AccelerationBased`: k = ω², c = 2ζω). That
//! is one two-sided row per link along `P_a − P_b`, the same constraint as dsmcosim's
//! `w = |P_a − P_b| − L`, as stiff as Rapier's own rigid joints.
//!
//! **What is measured.** max |w| is the largest `| |P_a − P_b| − L |` over every link and
//! step, anchors `P = x + R r` (dsmcosim's definition, `System::violations`); dsmcosim's
//! is `CoSim::max_violation()` (checked at the start of every step), Rapier's is computed
//! after every step, outside the timed part. Timing is wall-clock (`Instant`) around
//! dsmcosim's `run_to_end` (which includes its own per-step |w| check) and around the sum
//! of Rapier's `PhysicsWorld::step` calls; both run on one thread (the world is
//! monolithic: one node, so dsmcosim's parallel lock-step has nothing to split; Rapier is
//! built without its `parallel` feature). body-steps/s = bodies × steps / seconds.
use std::io::Write;
use std::time::Instant;

use dsmcosim::cosim::CoSim;
use dsmcosim::scenario::{parse_str, Scenario};
use rapier3d_f64::prelude::*;
use serde_json::{json, Value};

/// Grid spacing L [m], body mass [kg] and cube edge [m]: the thesis grid's.
const SPACING: f64 = 1.8;
const MASS: f64 = 1.0;
const SIZE: f64 = 0.2;
/// Integration step [s], both engines.
const DT: f64 = 0.001;

/// Default simulated steps per grid size (dt = 1 ms): 2 s up to 32×32, 1 s at 64×64,
/// 0.25 s at 128×128, so a full run stays within minutes on a shared 2-core machine.
fn default_steps(n: usize) -> u64 {
    match n {
        0..=32 => 2000,
        33..=64 => 1000,
        _ => 250,
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Class {
    Loose,
    Tight,
}

impl Class {
    fn name(self) -> &'static str {
        match self {
            Class::Loose => "loose",
            Class::Tight => "tight",
        }
    }

    /// dsmcosim's settings for this class, as scenario keys.
    fn dsm_settings(self) -> Value {
        match self {
            // The thesis defaults (integrator, stabilizer) with CG 10.
            Class::Loose => json!({
                "solver": {"kind": "cg", "max_iterations": 10, "tolerance": 0.0}
            }),
            // scenarios/grid64_tight.json's settings.
            Class::Tight => json!({
                "integrator": "rk4",
                "stabilizer": {"kind": "smc", "mu": 0.002, "k": 200.0, "epsilon": 0.1},
                "solver": {"kind": "cholesky_pcg", "refactor_every": 20, "tolerance": 1e-8,
                           "max_iterations": 10},
            }),
        }
    }

    fn dsm_label(self) -> &'static str {
        match self {
            Class::Loose => "Euler, SMC μ 50 ms K 10, CG 10",
            Class::Tight => "RK4, SMC μ 2 ms K 200, cholesky_pcg",
        }
    }
}

/// Which Rapier joint stands for a distance link (see the crate docs).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum JointKind {
    /// Coupled linear axes with a stiff position motor at L: two-sided.
    Distance,
    /// Coupled linear axes with the limit [L, L]: Rapier solves it one-sided (a rope).
    Rope,
}

/// Rapier's knobs that the bench turns.
#[derive(Clone, Copy, Debug)]
struct RapierSettings {
    joint: JointKind,
    /// `num_solver_iterations`: substeps per step in Rapier's soft-TGS solver.
    substeps: usize,
    /// `num_internal_pgs_iterations` per substep.
    pgs: usize,
    /// `warmstart_joints`.
    warmstart_joints: bool,
}

impl RapierSettings {
    fn defaults(joint: JointKind) -> RapierSettings {
        let p = IntegrationParameters::default();
        RapierSettings {
            joint,
            substeps: p.num_solver_iterations,
            pgs: p.num_internal_pgs_iterations,
            warmstart_joints: p.warmstart_joints,
        }
    }

    fn label(&self) -> String {
        let mut s = format!("{} substeps, {} PGS", self.substeps, self.pgs);
        if self.warmstart_joints {
            s.push_str(", warm-started joints");
        }
        if self.joint == JointKind::Rope {
            s.push_str(", rope joint");
        }
        s
    }
}

/// One engine's measurement of one case.
#[derive(Clone, Debug)]
struct Measured {
    max_w: f64,
    secs: f64,
    body_steps: f64,
    /// Every body's centre at the end of the run [m].
    end: Vec<[f64; 3]>,
}

impl Measured {
    fn rate(&self) -> f64 {
        self.body_steps / self.secs
    }
}

/// The validated scenario of an `n`×`n` grid run for `steps` steps in `class`.
fn scenario(n: usize, class: Class, steps: u64, tight_exact: bool) -> Scenario {
    let mut v = json!({
        "name": format!("rapier_{}_{n}", class.name()),
        "seed": 1,
        "duration": steps as f64 * DT,
        "dt": DT,
        "model": {"grid": {"rows": n, "cols": n, "spacing": SPACING, "mass": MASS, "size": SIZE}},
        "forces": [{"body": 1, "amplitude": [0, 0, 20], "omega": 2.0}],
        // A run that breaks this stops with an error: the bench then reports it.
        "divergence": {"max_violation": 1.0},
        "measurement": {"period": steps as f64 * DT},
    });
    for (k, val) in class.dsm_settings().as_object().expect("object") {
        v[k] = val.clone();
    }
    if tight_exact && class == Class::Tight {
        v["solver"] = json!({"kind": "cholesky"});
    }
    parse_str(&v.to_string(), "rapier bench").expect("valid bench scenario")
}

/// Steps dsmcosim's world over the whole scenario, timed.
fn run_dsm(s: &Scenario) -> Result<Measured, String> {
    let mut world = CoSim::new(s);
    let start = Instant::now();
    world.run_to_end(&mut ()).map_err(|e| e.to_string())?;
    let secs = start.elapsed().as_secs_f64();
    // A monolithic world has one node holding every body.
    let mut end = vec![[0.0; 3]; s.bodies.len()];
    for node in world.nodes() {
        for (local, &b) in node.bodies.iter().enumerate() {
            let p = node.state.p[local];
            end[b] = [p.x, p.y, p.z];
        }
    }
    Ok(Measured {
        max_w: world.max_violation(),
        secs,
        body_steps: (s.bodies.len() as u64 * s.steps) as f64,
        end,
    })
}

fn v3(x: &impl std::ops::Index<usize, Output = f64>) -> Vector {
    Vector::new(x[0], x[1], x[2])
}

/// Rapier's world for scenario `s`: one dynamic body per body (no collider: dsmcosim has
/// no contacts, and none of Rapier's collision pipeline should be timed), one joint per
/// link, zero gravity.
struct RapierWorld {
    world: PhysicsWorld,
    bodies: Vec<RigidBodyHandle>,
    /// (body a, body b, anchor on a, anchor on b, rest length).
    links: Vec<(RigidBodyHandle, RigidBodyHandle, Vector, Vector, f64)>,
}

fn build_rapier(s: &Scenario, set: &RapierSettings) -> RapierWorld {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    let p = &mut world.integration_parameters;
    p.dt = s.dt.as_secs_f64();
    p.num_solver_iterations = set.substeps;
    p.num_internal_pgs_iterations = set.pgs;
    p.warmstart_joints = set.warmstart_joints;

    let bodies: Vec<RigidBodyHandle> = s
        .bodies
        .iter()
        .map(|b| {
            let q = b.orientation.quaternion();
            let rb = RigidBodyBuilder::dynamic()
                .pose(Pose::from_parts(
                    v3(&b.position),
                    Rotation::from_xyzw(q.i, q.j, q.k, q.w),
                ))
                // The body's mass and principal inertia, at its centre, with no collider.
                .additional_mass_properties(MassProperties::new(
                    Vector::ZERO,
                    b.mass,
                    v3(&b.inertia),
                ))
                // The net stays awake: dsmcosim never freezes a body either.
                .can_sleep(false)
                .build();
            world.bodies.insert(rb)
        })
        .collect();

    // Rapier's locked joint axes use SpringCoefficients::joint_defaults (1 MHz, ζ = 1);
    // the distance motor gets the same softness: with AccelerationBased k = ω², c = 2ζω,
    // its erp and cfm are those of a locked axis.
    let soft = SpringCoefficients::<Real>::joint_defaults();
    let omega = soft.angular_frequency();
    let (k, c) = (omega * omega, 2.0 * soft.damping_ratio * omega);

    let mut links = Vec::with_capacity(s.links.len());
    for l in &s.links {
        let (ra, rb) = (v3(&l.anchor_a), v3(&l.anchor_b));
        let builder = GenericJointBuilder::new(JointAxesMask::empty())
            .coupled_axes(JointAxesMask::LIN_AXES)
            .local_anchor1(ra)
            .local_anchor2(rb);
        let joint = match set.joint {
            JointKind::Distance => builder
                .motor_model(JointAxis::LinX, MotorModel::AccelerationBased)
                .motor_position(JointAxis::LinX, l.length, k, c)
                .motor_max_force(JointAxis::LinX, Real::MAX),
            JointKind::Rope => builder.limits(JointAxis::LinX, [l.length, l.length]),
        }
        .build();
        let (a, b) = (bodies[l.a], bodies[l.b]);
        world.impulse_joints.insert(a, b, joint, true);
        links.push((a, b, ra, rb, l.length));
    }
    RapierWorld {
        world,
        bodies,
        links,
    }
}

impl RapierWorld {
    /// max |w| over the links now, w = |P_a − P_b| − L with P = x + R r.
    fn max_w(&self) -> f64 {
        let anchor = |h: RigidBodyHandle, r: Vector| {
            let b = &self.world.bodies[h];
            b.translation() + *b.rotation() * r
        };
        self.links
            .iter()
            .map(|&(a, b, ra, rb, len)| ((anchor(a, ra) - anchor(b, rb)).length() - len).abs())
            .fold(0.0, f64::max)
    }
}

/// A self-check that Rapier's world is dsmcosim's before it steps: the same counts and
/// every link at its rest length (to round-off).
fn check_same_links(s: &Scenario, r: &RapierWorld) {
    assert_eq!(r.bodies.len(), s.bodies.len(), "body count");
    assert_eq!(r.links.len(), s.links.len(), "link count");
    assert_eq!(r.world.impulse_joints.len(), s.links.len(), "joint count");
    assert!(r.max_w() <= 1e-12, "links start at their rest lengths");
}

/// The same masses and principal inertias (Rapier computes a body's mass properties in
/// its first step, so this runs after it).
fn check_same_masses(s: &Scenario, r: &RapierWorld) {
    for (h, b) in r.bodies.iter().zip(&s.bodies) {
        let m = &r.world.bodies[*h].mass_properties().local_mprops;
        assert!((m.mass() - b.mass).abs() <= 1e-12 * b.mass, "mass");
        let i = m.principal_inertia();
        for k in 0..3 {
            assert!(
                (i[k] - b.inertia[k]).abs() <= 1e-12 * b.inertia[k],
                "inertia"
            );
        }
    }
}

/// Steps Rapier's world over scenario `s`; only `PhysicsWorld::step` is timed.
fn run_rapier(s: &Scenario, set: &RapierSettings) -> Result<Measured, String> {
    let mut r = build_rapier(s, set);
    check_same_links(s, &r);
    let dt = s.dt;
    let mut secs = 0.0;
    let mut max_w = 0.0f64;
    for step in 0..s.steps {
        // dsmcosim's force law, held over the step from its start (as explicit Euler).
        let t = dsmcosim::kernel::SimTime(step * dt.0);
        for f in &s.forces {
            let b = &mut r.world.bodies[r.bodies[f.body]];
            b.reset_forces(false);
            b.add_force(v3(&f.at(t)), true);
        }
        let start = Instant::now();
        r.world.step();
        secs += start.elapsed().as_secs_f64();
        if step == 0 {
            check_same_masses(s, &r);
        }
        let w = r.max_w();
        if !w.is_finite() {
            return Err(format!("Rapier diverged at step {step}: |w| = {w}"));
        }
        max_w = max_w.max(w);
    }
    let end = r
        .bodies
        .iter()
        .map(|&h| {
            let x = r.world.bodies[h].translation();
            [x.x, x.y, x.z]
        })
        .collect();
    Ok(Measured {
        max_w,
        secs,
        body_steps: (s.bodies.len() as u64 * s.steps) as f64,
        end,
    })
}

/// [`run_rapier`], with its result on stderr.
fn run_logged(s: &Scenario, set: &RapierSettings) -> Result<Measured, String> {
    let r = run_rapier(s, set);
    match &r {
        Ok(m) => eprintln!(
            "  Rapier ({}): max |w| {} m, {:.2} s, {}",
            set.label(),
            sci(m.max_w),
            m.secs,
            rate(m.rate())
        ),
        Err(e) => eprintln!("  Rapier ({}) failed: {e}", set.label()),
    }
    r
}

/// The fewest substeps at which Rapier's max |w| is at or below `target`, and that run.
///
/// Rapier's max |w| on these grids falls as the square of the substep length (the
/// drift of each substep's position update along a link that turns: 1.49e-5, 3.72e-6,
/// 9.29e-7, 2.33e-7 m at 1, 2, 4, 8 substeps on 16×16), so from a run at `k` substeps
/// the count that meets `target` is predicted as `⌈k √(max|w| / target)⌉`. The search
/// runs the current count, jumps to the prediction while the target is missed (at least
/// one more substep each time, at most `max` substeps), and, once it is met, tries one
/// substep fewer while that still meets it, so the count timed is the smallest that
/// meets the target (on the way down the prediction is not trusted: a count is only
/// kept when its own run met the target).
fn search_substeps(
    s: &Scenario,
    set: &mut RapierSettings,
    target: f64,
    max: usize,
) -> Result<Measured, String> {
    let mut best: Option<(usize, Measured)> = None;
    let mut tried = std::collections::BTreeMap::new();
    loop {
        let r = run_logged(s, set)?;
        let w = r.max_w;
        tried.insert(set.substeps, w);
        let met = w <= target;
        if met && best.as_ref().is_none_or(|(k, _)| set.substeps < *k) {
            best = Some((set.substeps, r));
        }
        let next = if met {
            set.substeps - 1
        } else {
            let k = set.substeps as f64 * (w / target).sqrt();
            (k.ceil() as usize).max(set.substeps + 1).min(max)
        };
        if next == 0 || tried.contains_key(&next) || (!met && set.substeps >= max) {
            break;
        }
        set.substeps = next;
    }
    match best {
        Some((k, m)) => {
            set.substeps = k;
            Ok(m)
        }
        // The target was not met within `max` substeps: report the last (tightest) run.
        None => {
            eprintln!(
                "  Rapier did not reach {} m within {max} substeps",
                sci(target)
            );
            run_rapier(s, set)
        }
    }
}

/// Command line.
struct Args {
    grids: Vec<usize>,
    classes: Vec<Class>,
    steps: Option<u64>,
    joint: JointKind,
    substeps: Option<usize>,
    loose_substeps: Option<usize>,
    warmstart_joints: bool,
    max_substeps: usize,
    /// The tight class on `cholesky` (factorized every solve) instead of `cholesky_pcg`.
    tight_exact: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        grids: vec![16, 32, 64, 128],
        classes: vec![Class::Loose, Class::Tight],
        steps: None,
        joint: JointKind::Distance,
        substeps: None,
        loose_substeps: None,
        warmstart_joints: false,
        max_substeps: 1024,
        tight_exact: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        let num = |v: &str| v.parse::<usize>().map_err(|e| format!("{flag} {v}: {e}"));
        match flag.as_str() {
            "--grids" => a.grids = value()?.split(',').map(num).collect::<Result<_, _>>()?,
            "--classes" => {
                a.classes = value()?
                    .split(',')
                    .map(|c| match c {
                        "loose" => Ok(Class::Loose),
                        "tight" => Ok(Class::Tight),
                        _ => Err(format!("unknown class {c} (loose, tight)")),
                    })
                    .collect::<Result<_, _>>()?
            }
            "--steps" => a.steps = Some(num(&value()?)? as u64),
            "--joint" => {
                a.joint = match value()?.as_str() {
                    "distance" => JointKind::Distance,
                    "rope" => JointKind::Rope,
                    j => return Err(format!("unknown joint {j} (distance, rope)")),
                }
            }
            "--substeps" => a.substeps = Some(num(&value()?)?),
            "--loose-substeps" => a.loose_substeps = Some(num(&value()?)?),
            "--warmstart-joints" => a.warmstart_joints = true,
            "--max-substeps" => a.max_substeps = num(&value()?)?,
            "--tight-exact" => a.tight_exact = true,
            "-h" | "--help" => {
                println!(
                    "usage: rapier-bench [--grids 16,32,64,128] [--classes loose,tight] \
                     [--steps N] [--joint distance|rope] [--substeps N] \
                     [--loose-substeps N] [--warmstart-joints] [--max-substeps N] \
                     [--tight-exact]"
                );
                std::process::exit(0);
            }
            f => return Err(format!("unknown argument {f}")),
        }
    }
    Ok(a)
}

/// The largest distance between the two engines' end positions of one body [m]: how
/// far apart the two runs' motions ended (max |w| alone does not say that the motion
/// is right).
fn max_gap(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max)
}

/// `1.23e-4`.
fn sci(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    format!("{x:.2e}")
}

/// `4.30 M` / `259 k`.
fn rate(x: f64) -> String {
    if x >= 1e6 {
        format!("{:.2} M", x / 1e6)
    } else {
        format!("{:.0} k", x / 1e3)
    }
}

fn main() {
    let args = parse_args().unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
    let mut rows = Vec::new();
    for &n in &args.grids {
        let steps = args.steps.unwrap_or_else(|| default_steps(n));
        for &class in &args.classes {
            let s = scenario(n, class, steps, args.tight_exact);
            eprintln!(
                "{n}×{n} {}: {} bodies, {} links, {steps} steps",
                class.name(),
                s.bodies.len(),
                s.links.len()
            );
            let dsm = run_dsm(&s);
            match &dsm {
                Ok(m) => eprintln!(
                    "  dsmcosim: max |w| {} m, {:.2} s, {}",
                    sci(m.max_w),
                    m.secs,
                    rate(m.rate())
                ),
                Err(e) => eprintln!("  dsmcosim failed: {e}"),
            }
            // Rapier: defaults for loose; for tight, the fewest substeps at which its max |w|
            // is at or below dsmcosim's (up to --max-substeps), unless --substeps fixes them.
            let mut set = RapierSettings::defaults(args.joint);
            if class == Class::Tight {
                set.warmstart_joints = args.warmstart_joints;
            }
            let fixed = match class {
                Class::Loose => args.loose_substeps,
                Class::Tight => args.substeps,
            };
            if let Some(k) = fixed {
                set.substeps = k;
            }
            let target = match (&dsm, class) {
                (Ok(m), Class::Tight) if args.substeps.is_none() => Some(m.max_w),
                _ => None,
            };
            let rap = match target {
                None => run_logged(&s, &set),
                Some(t) => search_substeps(&s, &mut set, t, args.max_substeps),
            };
            let row = format!(
                "| {n}×{n} | {steps} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                class.name(),
                if args.tight_exact && class == Class::Tight {
                    "RK4, SMC μ 2 ms K 200, cholesky"
                } else {
                    class.dsm_label()
                },
                dsm.as_ref().map_or("failed".into(), |m| sci(m.max_w)),
                dsm.as_ref().map_or("—".into(), |m| rate(m.rate())),
                set.label(),
                rap.as_ref().map_or("failed".into(), |m| sci(m.max_w)),
                rap.as_ref().map_or("—".into(), |m| rate(m.rate())),
                match (&dsm, &rap) {
                    (Ok(d), Ok(r)) => format!("{:.2}×", d.rate() / r.rate()),
                    _ => "—".into(),
                },
                match (&dsm, &rap) {
                    (Ok(d), Ok(r)) => sci(max_gap(&d.end, &r.end)),
                    _ => "—".into(),
                }
            );
            eprintln!("{row}");
            rows.push(row);
        }
    }
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "| grid | steps (dt 1 ms) | accuracy | dsmcosim settings | dsmcosim max \\|w\\| [m] | \
         dsmcosim body-steps/s | Rapier settings | Rapier max \\|w\\| [m] | \
         Rapier body-steps/s | dsmcosim ÷ Rapier | end positions apart [m] |"
    )
    .and_then(|_| writeln!(out, "|---|---|---|---|---|---|---|---|---|---|---|"))
    .and_then(|_| rows.iter().try_for_each(|r| writeln!(out, "{r}")))
    .expect("stdout");
}
