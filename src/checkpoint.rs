//! Checkpoints: the complete state of a run at a window or slice boundary, written
//! atomically as a versioned binary file, from which `dsmcosim resume` finishes the run
//! with the same digest as an uninterrupted one.
//!
//! A checkpoint holds the whole world (kernel queue with every pending event and message
//! in flight, every node's state, ghosts, held values and solver warm starts, channels,
//! measurement windows — the scenario included), the recorder (digest chain, plot series,
//! the trace lines so far) and the controller (simplex searches, everything measured).
//!
//! Layout: the 16-byte magic `DSMCOSIM-CKPT\0\0\0`, the layout version as a
//! little-endian `u32`, the 32-byte BLAKE3 hash of the body, then the body: the state in
//! `postcard` encoding, which stores every `f64` as its exact bits (infinities and NaN
//! included, which JSON cannot hold). The TDMA network's random streams (clock drift,
//! random walk, sync error, jitter) are part of the world, positions included.
//!
//! The hash is checked before anything is decoded, so a flipped bit anywhere in the
//! body or the hash, a truncated or extended file, is refused rather than decoded into
//! a different state (postcard alone accepts many such changes: most byte patterns are
//! valid varints and floats).

use std::path::{Path, PathBuf};

use crate::control::experiment::Controller;
use crate::cosim::CoSim;
use crate::error::{Error, Result};
use crate::kernel::SimTime;
use crate::output::{create_dir_all, write_atomic};
use crate::trace::Recorder;

/// The first bytes of every checkpoint file.
pub const MAGIC: &[u8; 16] = b"DSMCOSIM-CKPT\0\0\0";
/// The checkpoint layout version this binary reads and writes; bumped whenever any
/// serialized type changes.
pub const VERSION: u32 = 25;
/// Length of the header: magic, version, body hash [bytes].
const HEADER: usize = 16 + 4 + 32;

/// A run's complete state.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Checkpoint {
    /// The `dsmcosim` version that wrote it (informative).
    pub writer: String,
    /// Simulated time of the checkpoint.
    pub time: SimTime,
    /// The world.
    pub world: CoSim,
    /// The recorder.
    pub recorder: Recorder,
    /// The controller, for controlled runs.
    pub controller: Option<Controller>,
}

#[derive(serde::Serialize)]
struct CheckpointRef<'a> {
    writer: String,
    time: SimTime,
    world: &'a CoSim,
    recorder: &'a Recorder,
    controller: Option<&'a Controller>,
}

/// File name of the checkpoint at `t`: `t_<seconds, 6 digits>.<nanoseconds, 9>.ckpt`.
pub fn file_name(t: SimTime) -> String {
    format!(
        "t_{:06}.{:09}.ckpt",
        t.0 / crate::kernel::time::NANOS_PER_SEC,
        t.0 % crate::kernel::time::NANOS_PER_SEC
    )
}

/// Writes the checkpoint at `time` into `out/checkpoints/` and returns its path.
pub fn write(
    out: &Path,
    time: SimTime,
    world: &CoSim,
    recorder: &Recorder,
    controller: Option<&Controller>,
) -> Result<PathBuf> {
    let dir = out.join("checkpoints");
    create_dir_all(&dir)?;
    let path = dir.join(file_name(time));
    let bytes = to_bytes(time, world, recorder, controller)
        .map_err(|e| Error::io(&path, std::io::Error::other(e)))?;
    write_atomic(&path, &bytes)?;
    Ok(path)
}

/// The bytes of the checkpoint at `time`, as [`write`] stores them (magic, version,
/// BLAKE3 of the state, the state): what an embedding keeps in memory (the Python
/// package pickles a co-simulation as these).
pub fn to_bytes(
    time: SimTime,
    world: &CoSim,
    recorder: &Recorder,
    controller: Option<&Controller>,
) -> std::result::Result<Vec<u8>, postcard::Error> {
    let mut bytes = MAGIC.to_vec();
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    let body = postcard::to_stdvec(&CheckpointRef {
        writer: env!("CARGO_PKG_VERSION").to_string(),
        time,
        world,
        recorder,
        controller,
    })?;
    bytes.extend_from_slice(blake3::hash(&body).as_bytes());
    bytes.extend_from_slice(&body);
    Ok(bytes)
}

/// The bytes of a checkpoint file: the first 20 (magic and version) alone unless they
/// are a checkpoint's, else the whole file up to the memory bound.
fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::new();
    let head = (MAGIC.len() + 4) as u64;
    (&mut file)
        .take(head)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 == head
        && &bytes[..MAGIC.len()] == MAGIC
        && bytes[MAGIC.len()..] == VERSION.to_le_bytes()
    {
        let cap = crate::input::DEFAULT_MAX_MEMORY_BYTES;
        file.take(cap)
            .read_to_end(&mut bytes)
            .map_err(|e| Error::io(path, e))?;
    }
    Ok(bytes)
}

/// Reads a checkpoint; a truncated, corrupted or foreign file is a clear error.
///
/// The magic bytes and the version are read and checked first, so that a file that is no
/// checkpoint (`/dev/zero`, any stream) is refused after 20 bytes instead of read whole;
/// the rest is read up to [`crate::input::DEFAULT_MAX_MEMORY_BYTES`].
pub fn read(path: &Path) -> Result<Checkpoint> {
    let bytes = read_bytes(path)?;
    from_bytes(&bytes, &path.display().to_string())
}

/// The checkpoint held in `bytes` ([`to_bytes`]'s), checked as [`read`] checks a file;
/// errors name `label`.
pub fn from_bytes(bytes: &[u8], label: &str) -> Result<Checkpoint> {
    let label = label.to_string();
    if bytes.len() < MAGIC.len() + 4 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(Error::invalid(
            label,
            "not a dsmcosim checkpoint (bad magic bytes)",
        ));
    }
    let version = u32::from_le_bytes(
        bytes[MAGIC.len()..MAGIC.len() + 4]
            .try_into()
            .expect("ok: four bytes"),
    );
    if version != VERSION {
        return Err(Error::invalid(
            label,
            format!(
                "checkpoint version {version} cannot be read by this binary (it reads version {VERSION})"
            ),
        ));
    }
    if bytes.len() < HEADER {
        return Err(Error::invalid(
            label,
            "corrupted or truncated checkpoint: the header is incomplete",
        ));
    }
    let body = &bytes[HEADER..];
    if blake3::hash(body).as_bytes()[..] != bytes[MAGIC.len() + 4..HEADER] {
        return Err(Error::invalid(
            label,
            "corrupted or truncated checkpoint: the BLAKE3 hash of its state does not match \
             the one in its header",
        ));
    }
    let (cp, rest): (Checkpoint, &[u8]) =
        postcard::take_from_bytes(body).map_err(|e| corrupt(&label, &e))?;
    if !rest.is_empty() {
        return Err(Error::invalid(
            label,
            format!(
                "corrupted checkpoint: {} unexpected bytes after the state",
                rest.len()
            ),
        ));
    }
    Ok(cp)
}

fn corrupt(label: &str, e: &postcard::Error) -> Error {
    Error::invalid(label, format!("corrupted or truncated checkpoint: {e}"))
}
