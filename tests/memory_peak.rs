//! The memory estimate against the measured peak, in a test binary of its own.
//!
//! The peak is the child's `ru_maxrss` from `wait4`, which also counts the memory the
//! child shared with its parent before `exec`: spawned from the many-threaded `cli`
//! test binary in the middle of the suite it read 63 MB for a 21 MB run. Alone in a
//! small binary, the parent's share is a few MB.

use std::path::PathBuf;
use std::process::{Command, Stdio};

use serde_json::json;

#[path = "support/memory_grid.rs"]
mod memory_grid;
use memory_grid::{joint_chain, memory_grid};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
}

fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("test-scratch")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// The estimate `validate` prints [MB].
fn estimated_mb(file: &str) -> u64 {
    let o = bin().args(["validate", file]).output().expect("validate");
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let at = text.find("needs about ").expect("an estimate") + "needs about ".len();
    text[at..].split(' ').next().unwrap().parse().expect("MB")
}

/// The memory estimate bounds the measured peak resident memory (the child's own
/// `ru_maxrss`, from `wait4`) of 10 steps on 64×64 and 128×128 grids, on both solves,
/// and on chains of 5000 welds and 20 000 ball joints (more rows per body than a grid's).
/// What is asserted is memory, not time.
#[test]
fn estimate_bounds_the_measured_peak() {
    let dir = scratch("limits-memory");
    let cg = json!({"kind": "cg", "max_iterations": 10, "tolerance": 1e-9});
    // Each scene is built when its turn comes and dropped before the child starts: the
    // child's peak counts what this process holds at the fork.
    type Scene = Box<dyn Fn() -> serde_json::Value>;
    let mut scenes: Vec<(String, Scene)> = Vec::new();
    for n in [64, 128] {
        for (name, solver) in [("exact", None), ("cg", Some(cg.clone()))] {
            scenes.push((
                format!("{n}×{n} {name}"),
                Box::new(move || memory_grid(n, solver.clone())),
            ));
        }
    }
    scenes.push(("5000 welds".into(), Box::new(|| joint_chain(5000, "weld"))));
    scenes.push((
        "20 000 balls".into(),
        Box::new(|| joint_chain(20_000, "ball")),
    ));
    for (i, (name, scene)) in scenes.into_iter().enumerate() {
        {
            let file = dir.join(format!("scene{i}.json"));
            std::fs::write(&file, scene().to_string()).expect("write");
            let f = file.to_str().unwrap();
            let estimate = estimated_mb(f);
            let out = dir.join(format!("scene{i}_out"));
            // Reaped by `wait4` below, which also reports its peak memory.
            #[allow(clippy::zombie_processes)]
            let child = bin()
                .args(["run", f, "--out", out.to_str().unwrap()])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("spawn dsmcosim");
            let mut status = 0;
            // SAFETY: `rusage` is plain data, zero is a valid value of it.
            let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
            // SAFETY: waits for our own child, writing through valid exclusive pointers;
            // `child` is not waited again (std's wait would find it reaped).
            let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
            assert_eq!(pid, child.id() as libc::pid_t, "wait4");
            assert!(
                libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
                "{name}: run failed"
            );
            let peak_mb = (usage.ru_maxrss as u64 * 1024).div_ceil(1_000_000);
            assert!(
                peak_mb <= estimate,
                "{name}: measured {peak_mb} MB above the estimate {estimate} MB"
            );
            eprintln!("{name}: peak {peak_mb} MB, estimate {estimate} MB");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
