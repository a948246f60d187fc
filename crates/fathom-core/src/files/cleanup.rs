//! Temporary files that must not outlive the process: the half-written outputs of
//! [`crate::atomic_file`] and the spool files of streamed writers. Each is registered here
//! when it is created and unregistered when it is removed or renamed into place; a
//! [`Pending`] guard removes its file when dropped (an error, a panic's unwinding), and
//! [`interrupted`], which a command-line program calls from its Ctrl-C / SIGTERM handler,
//! removes every registered file before the process exits. Only SIGKILL (or a power cut)
//! can leave one behind, and then under a hidden name, never under the final one.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

/// The registered files by id.
static PENDING: Mutex<Vec<(u64, PathBuf)>> = Mutex::new(Vec::new());
static NEXT_ID: AtomicU64 = AtomicU64::new(0);

fn pending() -> MutexGuard<'static, Vec<(u64, PathBuf)>> {
    // A panic while the lock was held leaves the list itself intact.
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// A registered temporary file: removed (and unregistered) when dropped, unless
/// [`Pending::rename_to`] moved it into place.
#[derive(Debug)]
pub struct Pending {
    id: u64,
    path: PathBuf,
}

impl Pending {
    /// Registers `path` and creates it with `create`, both under the registry's lock, so an
    /// interruption can never see a created file that is not registered. Nothing stays
    /// registered when `create` fails.
    pub fn create<T>(
        path: PathBuf,
        create: impl FnOnce(&Path) -> std::io::Result<T>,
    ) -> std::io::Result<(Pending, T)> {
        let mut list = pending();
        let made = create(&path)?;
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        list.push((id, path.clone()));
        Ok((Pending { id, path }, made))
    }

    /// The temporary file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Renames the file to `to` and unregisters it, under the lock (an interruption either
    /// removes the temporary file before the rename or finds it already renamed). On an
    /// error the guard is handed back, still registered, so dropping it removes the file.
    pub fn rename_to(self, to: &Path) -> Result<(), (Pending, std::io::Error)> {
        let mut list = pending();
        if let Err(e) = std::fs::rename(&self.path, to) {
            drop(list);
            return Err((self, e));
        }
        list.retain(|(id, _)| *id != self.id);
        drop(list);
        std::mem::forget(self);
        Ok(())
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        let mut list = pending();
        let _ = std::fs::remove_file(&self.path);
        list.retain(|(id, _)| *id != self.id);
    }
}

/// Whether `path` is registered now (for tests and diagnostics).
pub fn is_registered(path: &Path) -> bool {
    pending().iter().any(|(_, p)| p == path)
}

/// Removes every registered temporary file and exits with status 130 (the shell's code for
/// an interruption). For a Ctrl-C / SIGTERM handler, which runs on its own thread: the lock
/// is kept until the process ends, so no other thread can register a new file meanwhile.
pub fn interrupted() -> ! {
    let list = pending();
    for (_, p) in list.iter() {
        let _ = std::fs::remove_file(p);
    }
    eprintln!(
        "fathom: interrupted; removed {} temporary file(s)",
        list.len()
    );
    std::process::exit(130)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dropped_guard_removes_its_file_and_a_renamed_one_keeps_it() {
        let dir = std::env::temp_dir().join(format!("fathom-cleanup-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tmp = dir.join(".a.part");
        let (g, f) = Pending::create(tmp.clone(), |p| std::fs::File::create_new(p)).unwrap();
        drop(f);
        assert!(tmp.exists() && is_registered(&tmp));
        drop(g);
        assert!(
            !tmp.exists() && !is_registered(&tmp),
            "dropping the guard removes the file"
        );
        let (g, _) = Pending::create(tmp.clone(), |p| std::fs::File::create_new(p)).unwrap();
        let done = dir.join("a.txt");
        g.rename_to(&done).unwrap();
        assert!(done.exists() && !tmp.exists());
        // A failed creation registers nothing; a failed rename hands the guard back.
        assert!(
            Pending::create(tmp.clone(), |_| Err::<(), _>(std::io::Error::other("no"))).is_err()
        );
        assert!(!is_registered(&tmp));
        let (g, _) = Pending::create(tmp.clone(), |p| std::fs::File::create_new(p)).unwrap();
        let (g, _) = g.rename_to(&dir.join("missing/a.txt")).unwrap_err();
        assert!(tmp.exists());
        drop(g);
        assert!(!tmp.exists());
        std::fs::remove_dir_all(&dir).ok();
    }
}
