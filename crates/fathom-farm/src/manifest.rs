//! The job directory and its manifest. `DIR/farm.json` holds the job's fingerprint (hash of
//! the scene text, the render request, the work, the fathom version), its id (a hash of the
//! fingerprint) and the list of units with their file names; `DIR/scene.ron` the scene text.
//! Each finished unit gets a receipt `DIR/receipts/FILE.json` (job id, file, size, SHA-256)
//! written after its file: tasks never write the same file, so no lock is needed. A unit is
//! done when its receipt names this job and its file has the receipt's size and checksum;
//! missing when its file does not exist; corrupt otherwise (rendered again by a rerun).

use crate::atomic;
use crate::error::FarmError;
use crate::work::{Unit, Work};
use fathom_render::RenderRequest;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// The manifest's file name.
pub const MANIFEST: &str = "farm.json";
/// The stored scene's file name.
pub const SCENE: &str = "scene.ron";
/// The receipts' directory.
pub const RECEIPTS: &str = "receipts";
/// Manifest format version.
pub const FORMAT: u32 = 1;

/// SHA-256 of `bytes`, as lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Everything the outputs depend on. Two jobs with the same fingerprint make the same bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fingerprint {
    /// The version of fathom that wrote the job.
    pub fathom_version: String,
    /// SHA-256 of the scene text (`scene.ron`).
    pub scene_sha256: String,
    /// The request, without threads (any count renders the same pixels) and region.
    pub request: RenderRequest,
    /// The kind of job and its size.
    pub work: Work,
}

impl Fingerprint {
    /// The fingerprint of rendering `work` of the scene `scene_text` with `request`.
    pub fn new(scene_text: &str, request: &RenderRequest, work: Work) -> Result<Self, FarmError> {
        if request.region.is_some() {
            return Err(FarmError::Request(
                "it already has a region; the farm cuts the image itself".into(),
            ));
        }
        request
            .validate()
            .map_err(|e| FarmError::Request(e.to_string()))?;
        work.validate(request.output_size())?;
        Ok(Fingerprint {
            fathom_version: env!("CARGO_PKG_VERSION").into(),
            scene_sha256: sha256_hex(scene_text.as_bytes()),
            request: RenderRequest {
                threads: None,
                ..request.clone()
            },
            work,
        })
    }

    /// The job id: the first 16 hex digits of the SHA-256 of the fingerprint's JSON.
    pub fn id(&self) -> String {
        job_id(&serde_json::to_string(self).expect("a fingerprint serialises"))
    }
}

/// The job id of a fingerprint's compact JSON: its SHA-256's first 16 hex digits.
fn job_id(json: &str) -> String {
    sha256_hex(json.as_bytes())[..16].into()
}

/// The fields (dotted paths) that `ours` (this build's fingerprint as JSON) has and the
/// stored JSON `stored` lacks: settings added to fathom after the manifest was written (objects are compared
/// field by field; lists are not walked: the fingerprint holds none that could gain one).
fn missing_fields(stored: &serde_json::Value, ours: &serde_json::Value) -> Vec<String> {
    fn walk(stored: &serde_json::Value, ours: &serde_json::Value, at: &str, out: &mut Vec<String>) {
        let (Some(s), Some(o)) = (stored.as_object(), ours.as_object()) else {
            return;
        };
        for (k, v) in o {
            let path = if at.is_empty() {
                k.clone()
            } else {
                format!("{at}.{k}")
            };
            match s.get(k) {
                Some(sv) => walk(sv, v, &path, out),
                None => out.push(path),
            }
        }
    }
    let mut out = Vec::new();
    walk(stored, ours, "", &mut out);
    out
}

/// The job id a build without the scalar fields `missing` (dotted paths) would have given
/// `fingerprint` (`ours` as JSON): its compact JSON with each `,"field":value` left out. `None` when a field
/// cannot be left out that way (an object or list, or the first field of its object). Only a
/// hash that equals the stored job id shows the manifest is an earlier build's, untouched.
fn earlier_id(
    fingerprint: &Fingerprint,
    ours: &serde_json::Value,
    missing: &[String],
) -> Option<String> {
    let mut json = serde_json::to_string(fingerprint).ok()?;
    for path in missing {
        let v = path.split('.').try_fold(ours, |v, k| v.get(k))?;
        if v.is_object() || v.is_array() {
            return None;
        }
        let key = path.rsplit('.').next()?;
        let field = format!(",\"{key}\":{}", serde_json::to_string(v).ok()?);
        if !json.contains(&field) {
            return None;
        }
        json = json.replacen(&field, "", 1);
    }
    Some(job_id(&json))
}

/// `DIR/farm.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The manifest format version ([`FORMAT`]).
    pub format: u32,
    /// The job id ([`Fingerprint::id`]).
    pub job: String,
    /// Everything the outputs depend on.
    pub fingerprint: Fingerprint,
    /// Size of the output image (both eyes for stereo).
    pub output: (u32, u32),
    /// Every unit of the job, in index order.
    pub units: Vec<Unit>,
}

/// `DIR/receipts/FILE.json`: a unit's file as it was written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Receipt {
    /// The id of the job the unit belongs to.
    pub job: String,
    /// The unit's index.
    pub unit: usize,
    /// The unit's file name in the job directory.
    pub file: String,
    /// The file's size, bytes.
    pub size: u64,
    /// The SHA-256 of the file, hex.
    pub sha256: String,
}

/// A unit's state on disk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UnitState {
    /// Its file matches this receipt.
    Done(Receipt),
    /// Its file is not there (a receipt without its file counts as missing).
    Missing,
    /// Present but not trustworthy (why).
    Corrupt(String),
}

/// What `farm status` reports.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Status {
    /// The job id.
    pub job: String,
    /// Units in the job.
    pub units: usize,
    /// The units done.
    pub done: Vec<usize>,
    /// The units not yet rendered.
    pub missing: Vec<usize>,
    /// Unit and why.
    pub corrupt: Vec<(usize, String)>,
}

impl Status {
    /// Whether every unit is done.
    pub fn complete(&self) -> bool {
        self.done.len() == self.units
    }
}

/// An open job directory.
#[derive(Clone, Debug)]
pub struct FarmDir {
    /// The job directory.
    pub dir: PathBuf,
    /// Its manifest.
    pub manifest: Manifest,
}

/// Largest `farm.json` read, in bytes.
pub const MAX_MANIFEST_BYTES: u64 = 64 << 20;
/// Largest receipt read, in bytes.
pub const MAX_RECEIPT_BYTES: u64 = 1 << 20;
/// Largest unit file (a tile or frame PNG) read, in bytes: a 16384 x 16384 16-bit RGB image
/// stored uncompressed is 1.5 GiB.
pub const MAX_UNIT_BYTES: u64 = 2 << 30;

/// Reads `path` if it is a regular file of at most `max` bytes (a FIFO or `/dev/zero` behind
/// a symlink is refused before reading).
fn read_capped(path: &Path, max: u64) -> std::io::Result<Vec<u8>> {
    use fathom_core::input_file::{self, ReadError};
    input_file::read(path, max).map_err(|e| match e {
        ReadError::Io { source, .. } => source,
        other => std::io::Error::other(other.reason()),
    })
}

fn read(path: &Path) -> Result<Vec<u8>, FarmError> {
    read_capped(path, MAX_MANIFEST_BYTES).map_err(|source| FarmError::Read {
        path: path.into(),
        source,
    })
}

/// A manifest parse error, naming the unit entry at fault when it is one of them (serde's
/// own message gives only a line and column, the same for every entry of a one-line file).
fn which_entry(bytes: &[u8], e: serde_json::Error) -> String {
    let Ok(v) = serde_json::from_slice::<serde_json::Value>(bytes) else {
        return e.to_string();
    };
    if let Some(units) = v.get("units").and_then(|u| u.as_array()) {
        for (i, u) in units.iter().enumerate() {
            if let Err(ue) = serde_json::from_value::<crate::work::Unit>(u.clone()) {
                let file = u.get("file").and_then(|f| f.as_str()).unwrap_or("?");
                return format!("units[{i}] (`{file}`): {ue}");
            }
        }
    }
    e.to_string()
}

fn damaged(path: &Path, why: impl ToString) -> FarmError {
    FarmError::Damaged {
        path: path.into(),
        why: why.to_string(),
    }
}

impl FarmDir {
    /// Opens `dir` for the job `fingerprint` of `scene_text`, creating it (with its manifest
    /// and scene) when new. A directory holding another job is refused, naming what differs.
    pub fn create(
        dir: &Path,
        fingerprint: Fingerprint,
        scene_text: &str,
    ) -> Result<FarmDir, FarmError> {
        let job = fingerprint.id();
        if dir.join(MANIFEST).exists() {
            let existing = FarmDir::open(dir)?;
            if existing.manifest.job != job {
                let old = &existing.manifest.fingerprint;
                let new = &fingerprint;
                let what = if old.fathom_version != new.fathom_version {
                    format!(
                        "fathom version ({} then, {} now)",
                        old.fathom_version, new.fathom_version
                    )
                } else if old.scene_sha256 != new.scene_sha256 {
                    "the scene".into()
                } else if old.work != new.work {
                    "the work (tiles or frames)".into()
                } else {
                    "the render request".into()
                };
                return Err(FarmError::DifferentJob {
                    dir: dir.into(),
                    what,
                    existing: existing.manifest.job,
                    new: job,
                });
            }
            return Ok(existing);
        }
        let output = fingerprint.request.output_size();
        let manifest = Manifest {
            format: FORMAT,
            job,
            units: fingerprint.work.units(output),
            output,
            fingerprint,
        };
        std::fs::create_dir_all(dir.join(RECEIPTS)).map_err(|source| FarmError::Write {
            path: dir.join(RECEIPTS),
            source,
        })?;
        // The scene first (a manifest never exists without its scene), each created only if
        // absent: of two jobs racing into a new directory, one wins each name and the other
        // is refused, never mixed in; tasks of one job write identical bytes.
        if !atomic::create_exclusive(&dir.join(SCENE), scene_text.as_bytes())?
            && std::fs::read(dir.join(SCENE)).ok().as_deref() != Some(scene_text.as_bytes())
            && !dir.join(MANIFEST).exists()
        {
            return Err(FarmError::DifferentJob {
                dir: dir.into(),
                what: "the scene".into(),
                existing: "(being created, or left by an interrupted creation)".into(),
                new: manifest.job,
            });
        }
        let json = serde_json::to_vec_pretty(&manifest).expect("a manifest serialises");
        if !atomic::create_exclusive(&dir.join(MANIFEST), &json)? {
            // Another task created it meanwhile: same job, or refused.
            return FarmDir::create(dir, manifest.fingerprint, scene_text);
        }
        Ok(FarmDir {
            dir: dir.into(),
            manifest,
        })
    }

    /// Opens an existing job directory.
    pub fn open(dir: &Path) -> Result<FarmDir, FarmError> {
        let path = dir.join(MANIFEST);
        if !path.exists() {
            return Err(FarmError::NotAFarm {
                dir: dir.into(),
                manifest: MANIFEST,
            });
        }
        let bytes = read(&path)?;
        let manifest: Manifest =
            serde_json::from_slice(&bytes).map_err(|e| damaged(&path, which_entry(&bytes, e)))?;
        if manifest.format != FORMAT {
            return Err(damaged(
                &path,
                format!("format {} (this fathom reads {FORMAT})", manifest.format),
            ));
        }
        if manifest.job != manifest.fingerprint.id() {
            // Read with this build's defaults, a manifest from a build whose settings had
            // fewer fields fingerprints differently: say so rather than "damaged".
            let ours = serde_json::to_value(&manifest.fingerprint).expect("it serialises");
            let missing = serde_json::from_slice::<serde_json::Value>(&bytes)
                .map(|v| missing_fields(&v["fingerprint"], &ours))
                .unwrap_or_default();
            if !missing.is_empty()
                && earlier_id(&manifest.fingerprint, &ours, &missing).as_ref()
                    == Some(&manifest.job)
            {
                let missing = missing
                    .iter()
                    .map(|m| m.strip_prefix("request.").unwrap_or(m).to_string())
                    .collect();
                return Err(FarmError::Outdated { path, missing });
            }
            return Err(damaged(&path, "its job id does not match its fingerprint"));
        }
        let want = manifest.fingerprint.work.units(manifest.output);
        if manifest.units != want {
            let why = match manifest.units.iter().zip(&want).position(|(a, b)| a != b) {
                Some(i) => format!(
                    "unit {i} (`{}`) is not the unit its work defines there (`{}`)",
                    manifest.units[i].file, want[i].file
                ),
                None => format!(
                    "it lists {} units; its work has {}",
                    manifest.units.len(),
                    want.len()
                ),
            };
            return Err(damaged(&path, why));
        }
        Ok(FarmDir {
            dir: dir.into(),
            manifest,
        })
    }

    /// The stored scene text, checked against the manifest's hash.
    pub fn scene_text(&self) -> Result<String, FarmError> {
        let path = self.dir.join(SCENE);
        let bytes = read(&path)?;
        if sha256_hex(&bytes) != self.manifest.fingerprint.scene_sha256 {
            return Err(FarmError::SceneChanged { path });
        }
        String::from_utf8(bytes).map_err(|e| damaged(&path, e))
    }

    /// The path of a unit's file.
    pub fn path(&self, unit: &Unit) -> PathBuf {
        self.dir.join(&unit.file)
    }

    fn receipt_path(&self, unit: &Unit) -> PathBuf {
        self.dir.join(RECEIPTS).join(format!("{}.json", unit.file))
    }

    /// Unit `unit`'s state: its receipt and its file checked (size, then SHA-256).
    pub fn check(&self, unit: &Unit) -> UnitState {
        let file = self.path(unit);
        let rpath = self.receipt_path(unit);
        let bytes = match read_capped(&file, MAX_UNIT_BYTES) {
            Ok(b) => Some(b),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => return UnitState::Corrupt(format!("cannot read: {e}")),
        };
        let receipt = match read_capped(&rpath, MAX_RECEIPT_BYTES) {
            Ok(r) => match serde_json::from_slice::<Receipt>(&r) {
                Ok(r) => Some(r),
                Err(e) => return UnitState::Corrupt(format!("damaged receipt: {e}")),
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => return UnitState::Corrupt(format!("cannot read receipt: {e}")),
        };
        match (bytes, receipt) {
            // A receipt whose file is gone: the unit is missing (the receipt is replaced).
            (None, _) => UnitState::Missing,
            (Some(_), None) => UnitState::Corrupt("no receipt (interrupted write?)".into()),
            (Some(b), Some(r)) => {
                if r.job != self.manifest.job || r.unit != unit.index || r.file != unit.file {
                    UnitState::Corrupt(format!("receipt of another job or unit ({})", r.job))
                } else if b.len() as u64 != r.size {
                    UnitState::Corrupt(format!("{} bytes, the receipt says {}", b.len(), r.size))
                } else if sha256_hex(&b) != r.sha256 {
                    UnitState::Corrupt("checksum does not match the receipt".into())
                } else {
                    UnitState::Done(r)
                }
            }
        }
    }

    /// Every unit's state.
    pub fn status(&self) -> Status {
        let mut s = Status {
            job: self.manifest.job.clone(),
            units: self.manifest.units.len(),
            ..Status::default()
        };
        for u in &self.manifest.units {
            match self.check(u) {
                UnitState::Done(_) => s.done.push(u.index),
                UnitState::Missing => s.missing.push(u.index),
                UnitState::Corrupt(why) => s.corrupt.push((u.index, why)),
            }
        }
        s
    }

    /// Stores a finished unit: its file (through a temporary name), then its receipt; when the
    /// receipt cannot be written the file is removed again.
    pub fn commit(&self, unit: &Unit, bytes: &[u8]) -> Result<Receipt, FarmError> {
        let receipt = Receipt {
            job: self.manifest.job.clone(),
            unit: unit.index,
            file: unit.file.clone(),
            size: bytes.len() as u64,
            sha256: sha256_hex(bytes),
        };
        // An old receipt goes first: between the two writes the unit reads as corrupt, never
        // as done with the wrong bytes.
        let rpath = self.receipt_path(unit);
        match std::fs::remove_file(&rpath) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(source) => {
                return Err(FarmError::Write {
                    path: rpath,
                    source,
                });
            }
        }
        let file = self.path(unit);
        atomic::write(&file, bytes)?;
        let json = serde_json::to_vec_pretty(&receipt).expect("a receipt serialises");
        if let Err(e) = atomic::write(&rpath, &json) {
            // No receipt, no file: a final name is only ever seen with its receipt (but for
            // a task killed between the two renames, which reads as corrupt and is redone).
            let _ = std::fs::remove_file(&file);
            return Err(e);
        }
        Ok(receipt)
    }

    /// Verifies every unit; the units' files in order when all are done.
    pub fn verified(&self) -> Result<Vec<PathBuf>, FarmError> {
        let s = self.status();
        if !s.complete() {
            let units = &self.manifest.units;
            let mut bad: Vec<String> = s
                .missing
                .iter()
                .map(|&i| format!("{} missing", units[i].file))
                .collect();
            bad.extend(
                s.corrupt
                    .iter()
                    .map(|(i, why)| format!("{} corrupt: {why}", units[*i].file)),
            );
            return Err(FarmError::Incomplete {
                total: s.units,
                bad,
            });
        }
        Ok(self.manifest.units.iter().map(|u| self.path(u)).collect())
    }
}
