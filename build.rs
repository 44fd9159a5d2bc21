//! Build provenance for `summary.json`: the git commit the binary was built from (when
//! built inside a git checkout; `-dirty` when tracked files differ from it) and the
//! compiler's version. Read with `env!` in `src/run.rs`.

use std::path::Path;
use std::process::Command;

fn output(cmd: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(cmd).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    // Only paths that exist: a missing one would make cargo rerun this script on every
    // build (a copy of the sources without .git has none).
    for p in [".git/HEAD", ".git/index"] {
        if Path::new(p).exists() {
            println!("cargo:rerun-if-changed={p}");
        }
    }
    let commit = output("git", &["rev-parse", "HEAD"])
        .map(|c| {
            let dirty = output("git", &["status", "--porcelain", "--untracked-files=no"])
                .is_some_and(|s| !s.is_empty());
            if dirty {
                format!("{c}-dirty")
            } else {
                c
            }
        })
        .unwrap_or_default();
    println!("cargo:rustc-env=DSMCOSIM_GIT_COMMIT={commit}");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = output(&rustc, &["--version"]).unwrap_or_default();
    println!("cargo:rustc-env=DSMCOSIM_RUSTC={version}");
}
