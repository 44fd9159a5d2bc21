//! Builds the test FMUs (`tests/fmus/`: msd, pd, faulty, quirks, msd3 (msd in FMI 3.0
//! form), and types and types3 (an output of every FMI 2.0 and 3.0 type)) into a directory,
//! for the example scenarios that couple FMUs and for checking them with other FMI tools:
//!
//! ```text
//! cargo run --release --example build_fmus -- OUTDIR
//! ```
//!
//! Needs a C compiler (`$CC`, default `cc`).

use std::path::PathBuf;
use std::process::ExitCode;

#[path = "../tests/support/fmu_build.rs"]
mod fmu_build;

fn main() -> ExitCode {
    let mut args = std::env::args_os().skip(1);
    let (Some(out), None) = (args.next(), args.next()) else {
        eprintln!("usage: build_fmus OUTDIR");
        return ExitCode::from(2);
    };
    let out = PathBuf::from(out);
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("{}: {e}", out.display());
        return ExitCode::FAILURE;
    }
    for stem in fmu_build::TEST_FMUS {
        match fmu_build::build_test_fmu(stem, &out) {
            Ok(path) => println!("{}", path.display()),
            Err(e) => {
                eprintln!("{stem}: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    ExitCode::SUCCESS
}
