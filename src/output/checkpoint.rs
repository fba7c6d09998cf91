//! Checkpoints: the whole state of a run at a time level, to continue it bit for bit.
//!
//! The step of the scheme depends on nothing but the previous state (u, w, θ, ξ at t_{n−1}) and
//! the problem, so a run continued from a checkpoint of (n, t_n, u, w, θ, ξ) computes exactly
//! the steps the uninterrupted run would have (the matrices and factors are rebuilt the same
//! way, bitwise: see the assembly's note on threads).
//!
//! Format (`checkpoint.bin`, little-endian), written atomically:
//!
//! ```text
//! "TCCKPT" 0 1         magic and format version (8 bytes)
//! u64                  length of the header
//! header               JSON: identity (scenario and mesh fingerprints), n, t, array lengths,
//!                      and the run's record so far (opaque here, the driver's)
//! f64 × (…)            w, u, θ, ξ, s (the slip distances; absent in checkpoints written
//!                      before them, read as zeros), as the header's lengths say
//! [u8; 32]             SHA-256 of everything before it
//! ```
//!
//! Floats are stored as raw bits (no decimal round trip), so the continued run starts from the
//! same numbers. The checksum turns a damaged file into a clear refusal instead of a wrong run.
//! *Rejected*: a JSON or TOML state (10× larger, slow to write at 10⁶ unknowns) and a format
//! crate (bincode, …): the file is four arrays and a small header.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::mesh::Mesh;
use crate::model::State;

const MAGIC: &[u8; 8] = b"TCCKPT\x00\x01";

/// What a checkpoint belongs to: a continued run must have the same.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Identity {
    /// The scenario's fingerprint (everything that changes the solution; output choices excluded).
    pub scenario: Option<String>,
    /// The mesh's fingerprint ([`mesh_fingerprint`]).
    pub mesh: String,
}

/// A run's state at time level `state.n`, with the run's record so far.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    pub identity: Identity,
    pub state: State,
    /// The driver's record of the run so far (JSON).
    pub record: serde_json::Value,
}

#[derive(Serialize, Deserialize)]
struct Header {
    identity: Identity,
    n: usize,
    t: f64,
    /// w, u, θ, ξ and s (four where s predates the format: s = 0).
    lengths: Vec<usize>,
    record: serde_json::Value,
}

/// Why a checkpoint cannot be read or used.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read the checkpoint {}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{} is not a thermocontact checkpoint, or it is damaged: {reason}", path.display())]
    Damaged { path: PathBuf, reason: &'static str },
    #[error(
        "the checkpoint {} belongs to another {what} ({what} fingerprint {found}, this run's is {expected}); \
         a run continues only from its own checkpoints",
        path.display()
    )]
    Mismatch {
        path: PathBuf,
        what: &'static str,
        found: String,
        expected: String,
    },
    #[error(
        "the checkpoint {} is at step {step}, but the run has only {steps} steps",
        path.display()
    )]
    PastTheEnd { path: PathBuf, step: usize, steps: usize },
}

/// SHA-256 of the mesh (dimension, coordinates, cells, boundary facets and part names), hex.
pub fn mesh_fingerprint(mesh: &Mesh) -> String {
    let mut h = Sha256::new();
    h.update((mesh.dim as u64).to_le_bytes());
    h.update((mesh.coords.len() as u64).to_le_bytes());
    for x in &mesh.coords {
        for c in x {
            h.update(c.to_bits().to_le_bytes());
        }
    }
    for list in [&mesh.cells, &mesh.facets, &mesh.facet_parts] {
        h.update((list.len() as u64).to_le_bytes());
        for &i in list.iter() {
            h.update((i as u64).to_le_bytes());
        }
    }
    for name in &mesh.part_names {
        h.update((name.len() as u64).to_le_bytes());
        h.update(name.as_bytes());
    }
    hex(&h.finalize())
}

/// SHA-256 of a text, hex.
pub fn text_fingerprint(text: &str) -> String {
    hex(&Sha256::digest(text.as_bytes()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Writes `checkpoint` to `path` atomically.
pub fn write(path: &Path, checkpoint: &Checkpoint) -> std::io::Result<()> {
    let s = &checkpoint.state;
    let header = Header {
        identity: checkpoint.identity.clone(),
        n: s.n,
        t: s.t,
        lengths: arrays(s).map(|a| a.len()).collect(),
        record: checkpoint.record.clone(),
    };
    let header = serde_json::to_vec(&header).map_err(std::io::Error::other)?;
    crate::output::write_atomic_with(path, |w| {
        let mut hashed = Hashed {
            inner: w,
            hash: Sha256::new(),
        };
        hashed.write_all(MAGIC)?;
        hashed.write_all(&(header.len() as u64).to_le_bytes())?;
        hashed.write_all(&header)?;
        for array in arrays(s) {
            let mut bytes = Vec::with_capacity(8 * array.len());
            for v in array.iter() {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            hashed.write_all(&bytes)?;
        }
        let digest = hashed.hash.finalize();
        hashed.inner.write_all(&digest)
    })
}

struct Hashed<'a> {
    inner: &'a mut dyn Write,
    hash: Sha256,
}

impl Write for Hashed<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.update(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The arrays a checkpoint stores: w, u, θ, ξ, the slip distances, and the contact pressures
/// where a law scales with them (a sixth array only then, so that other runs' checkpoints keep
/// their bytes).
fn arrays(s: &State) -> impl Iterator<Item = &Vec<f64>> {
    [&s.w, &s.u, &s.theta, &s.xi, &s.slip_distance]
        .into_iter()
        .chain((!s.pressure.is_empty()).then_some(&s.pressure))
}

/// Reads a checkpoint, checking its format and checksum.
pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
    let bytes = crate::resources::read_input(path, crate::resources::max_data_file_bytes()).map_err(|source| {
        CheckpointError::Io {
            path: path.to_path_buf(),
            source,
        }
    })?;
    let damaged = |reason| CheckpointError::Damaged {
        path: path.to_path_buf(),
        reason,
    };
    if bytes.len() < MAGIC.len() + 8 + 32 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(damaged("it does not start with the checkpoint's magic bytes"));
    }
    let (body, digest) = bytes.split_at(bytes.len() - 32);
    if Sha256::digest(body).as_slice() != digest {
        return Err(damaged("its checksum does not match (a truncated or altered file)"));
    }
    let mut at = MAGIC.len();
    let header_len = u64::from_le_bytes(body[at..at + 8].try_into().expect("8 bytes")) as usize;
    at += 8;
    let header_bytes = body
        .get(at..at.saturating_add(header_len))
        .ok_or_else(|| damaged("its header is longer than the file"))?;
    let header: Header = serde_json::from_slice(header_bytes).map_err(|_| damaged("its header is not valid"))?;
    at += header_len;
    if !(4..=6).contains(&header.lengths.len()) {
        return Err(damaged("its header does not list four to six arrays"));
    }
    // Checked: a damaged header's lengths may overflow.
    let total = (header.lengths.iter()).try_fold(0usize, |sum, &len| sum.checked_add(len.checked_mul(8)?));
    if total != Some(body.len() - at) {
        return Err(damaged("its arrays do not have the lengths its header gives"));
    }
    let mut arrays = header.lengths.iter().map(|&len| {
        let values = body[at..at + 8 * len]
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
            .collect::<Vec<f64>>();
        at += 8 * len;
        values
    });
    let mut next = || arrays.next().unwrap_or_default();
    let state = State {
        n: header.n,
        t: header.t,
        w: next(),
        u: next(),
        theta: next(),
        xi: next(),
        slip_distance: next(),
        slip_distance_before: Vec::new(),
        pressure: next(),
        elastic_force: Vec::new(),
    };
    // Four arrays (a checkpoint older than the slip distances): `slip_distance` stays empty,
    // which the laws and the next step read as zeros.
    Ok(Checkpoint {
        identity: header.identity,
        state,
        record: header.record,
    })
}

impl Checkpoint {
    /// Checks that the checkpoint belongs to a run with `identity` and `steps` steps, whose
    /// state has the sizes of `like`.
    pub fn check(&self, path: &Path, identity: &Identity, steps: usize, like: &State) -> Result<(), CheckpointError> {
        let mismatch = |what, found: &str, expected: &str| CheckpointError::Mismatch {
            path: path.to_path_buf(),
            what,
            found: found.to_string(),
            expected: expected.to_string(),
        };
        if let (Some(found), Some(expected)) = (&self.identity.scenario, &identity.scenario) {
            if found != expected {
                return Err(mismatch("scenario", found, expected));
            }
        }
        if self.identity.mesh != identity.mesh {
            return Err(mismatch("mesh", &self.identity.mesh, &identity.mesh));
        }
        let s = &self.state;
        let sizes = |s: &State| [s.w.len(), s.u.len(), s.theta.len(), s.xi.len()];
        let slip_sizes_agree = s.slip_distance.is_empty() || s.slip_distance.len() == like.slip_distance.len();
        if sizes(s) != sizes(like) || !slip_sizes_agree {
            return Err(CheckpointError::Damaged {
                path: path.to_path_buf(),
                reason: "its fields do not have the sizes of this problem's",
            });
        }
        if s.n > steps {
            return Err(CheckpointError::PastTheEnd {
                path: path.to_path_buf(),
                step: s.n,
                steps,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> State {
        State {
            n: 7,
            t: 0.109375,
            w: vec![1.0 / 3.0, -0.0, f64::MIN_POSITIVE, 2.5e-300],
            u: vec![0.1, 0.2, 0.3, 0.4],
            theta: vec![25.0, 24.999999999999996],
            xi: vec![-149.99999999999997],
            slip_distance: vec![0.125],
            slip_distance_before: Vec::new(),
            pressure: Vec::new(),
            elastic_force: Vec::new(),
        }
    }

    /// A header whose array lengths overflow (with a valid checksum) is refused as damaged,
    /// not a panic.
    #[test]
    fn overflowing_lengths_are_damage() {
        let dir = std::env::temp_dir().join(format!("tc-ckpt-overflow-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("checkpoint.bin");
        let checkpoint = Checkpoint {
            identity: Identity {
                scenario: None,
                mesh: "m".into(),
            },
            state: state(),
            record: serde_json::json!({}),
        };
        write(&path, &checkpoint).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let at = MAGIC.len();
        let header_len = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
        let header = std::str::from_utf8(&bytes[at + 8..at + 8 + header_len]).unwrap();
        let huge = format!("\"lengths\":[{},{},4,1,1]", usize::MAX / 8 + 1, usize::MAX / 8 + 1);
        let start = header.find("\"lengths\":[").unwrap();
        let end = start + header[start..].find(']').unwrap() + 1;
        let forged = format!("{}{huge}{}", &header[..start], &header[end..]);
        let mut body = MAGIC.to_vec();
        body.extend((forged.len() as u64).to_le_bytes());
        body.extend(forged.as_bytes());
        body.extend(&bytes[at + 8 + header_len..bytes.len() - 32]);
        let digest = Sha256::digest(&body);
        body.extend(digest.as_slice());
        std::fs::write(&path, body).unwrap();
        let Err(error) = read(&path) else {
            panic!("a forged checkpoint was accepted")
        };
        assert!(matches!(error, CheckpointError::Damaged { .. }), "{error}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_checkpoint_reads_back_bit_for_bit_and_damage_is_refused() {
        let dir = std::env::temp_dir().join(format!("tc-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("checkpoint.bin");
        let identity = Identity {
            scenario: Some(text_fingerprint("a")),
            mesh: mesh_fingerprint(&crate::mesh::rectangle(1.0, 1.0, 1, 1)),
        };
        let checkpoint = Checkpoint {
            identity: identity.clone(),
            state: state(),
            record: serde_json::json!({"outputs": [1, 2]}),
        };
        write(&path, &checkpoint).unwrap();
        let back = read(&path).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let (a, b) = (&checkpoint.state, &back.state);
        assert_eq!((a.n, a.t.to_bits()), (b.n, b.t.to_bits()));
        for (x, y) in [
            (&a.w, &b.w),
            (&a.u, &b.u),
            (&a.theta, &b.theta),
            (&a.xi, &b.xi),
            (&a.slip_distance, &b.slip_distance),
        ] {
            assert_eq!(bits(x), bits(y));
        }
        assert_eq!(back.record, checkpoint.record);
        back.check(&path, &identity, 64, &state()).unwrap();

        let other = Identity {
            scenario: Some(text_fingerprint("b")),
            ..identity.clone()
        };
        let e = back.check(&path, &other, 64, &state()).unwrap_err().to_string();
        assert!(e.contains("another scenario"), "{e}");
        let e = back.check(&path, &identity, 5, &state()).unwrap_err().to_string();
        assert!(e.contains("step 7") && e.contains("5 steps"), "{e}");

        let mut bytes = std::fs::read(&path).unwrap();
        let middle = bytes.len() / 2;
        bytes[middle] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        assert!(read(&path).unwrap_err().to_string().contains("checksum"));
        std::fs::write(&path, &bytes[..40]).unwrap();
        assert!(matches!(read(&path), Err(CheckpointError::Damaged { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
