//! Opening, saving and watching scene files: a small file browser drawn with egui (the file
//! dialog crates for egui 0.37 either lag a version behind or need GTK's development packages,
//! which this project does not install), and a watcher that notices when the open file changes
//! on disk (its modification time, checked twice a second) so edits made in a text editor show
//! up at once.

use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

/// What the browser is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrowseFor {
    /// Choosing a scene file to open.
    Open,
    /// Choosing where to save the scene.
    Save,
}

/// The file browser window.
pub struct FileBrowser {
    /// What the browser is open for; `None` when it is closed.
    pub purpose: Option<BrowseFor>,
    dir: PathBuf,
    name: String,
    entries: Vec<(String, bool)>,
    error: Option<String>,
}

impl Default for FileBrowser {
    fn default() -> Self {
        FileBrowser {
            purpose: None,
            dir: std::env::current_dir().unwrap_or_else(|_| PathBuf::from(".")),
            name: String::new(),
            entries: Vec::new(),
            error: None,
        }
    }
}

impl FileBrowser {
    /// Opens the browser in `dir` (or where it was), proposing `name`.
    pub fn open(&mut self, purpose: BrowseFor, near: Option<&Path>) {
        if let Some(p) = near {
            if let Some(d) = p.parent().filter(|d| d.is_dir()) {
                self.dir = d.to_path_buf();
            }
            self.name = p
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
        }
        if purpose == BrowseFor::Save && self.name.is_empty() {
            self.name = "scene.ron".into();
        }
        self.purpose = Some(purpose);
        self.refresh();
    }

    fn refresh(&mut self) {
        self.entries.clear();
        match std::fs::read_dir(&self.dir) {
            Ok(rd) => {
                for e in rd.flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    let is_dir = e.file_type().map(|t| t.is_dir()).unwrap_or(false);
                    if is_dir || name.ends_with(".ron") {
                        self.entries.push((name, is_dir));
                    }
                }
                self.entries
                    .sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
                self.error = None;
            }
            Err(e) => self.error = Some(format!("{}: {e}", self.dir.display())),
        }
    }

    /// Draws the browser; returns the chosen path.
    pub fn show(&mut self, ctx: &egui::Context) -> Option<(BrowseFor, PathBuf)> {
        let purpose = self.purpose?;
        let mut chosen = None;
        let mut open = true;
        let title = match purpose {
            BrowseFor::Open => "Open scene",
            BrowseFor::Save => "Save scene as",
        };
        egui::Window::new(title)
            .open(&mut open)
            .collapsible(false)
            .default_size([420.0, 360.0])
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    if ui.button("Up").clicked()
                        && let Some(p) = self.dir.parent()
                    {
                        self.dir = p.to_path_buf();
                        self.refresh();
                    }
                    ui.label(self.dir.display().to_string());
                });
                ui.separator();
                let mut go = None;
                egui::ScrollArea::vertical()
                    .max_height(220.0)
                    .show(ui, |ui| {
                        for (name, is_dir) in &self.entries {
                            let label = if *is_dir {
                                format!("[{name}]")
                            } else {
                                name.clone()
                            };
                            let r = ui.selectable_label(*name == self.name, label);
                            if r.clicked() {
                                if *is_dir {
                                    go = Some(self.dir.join(name));
                                } else {
                                    self.name = name.clone();
                                }
                            }
                            if r.double_clicked() && !is_dir {
                                chosen = Some(self.dir.join(name));
                            }
                        }
                    });
                if let Some(d) = go {
                    self.dir = d;
                    self.refresh();
                }
                if let Some(e) = &self.error {
                    ui.colored_label(egui::Color32::LIGHT_RED, e);
                }
                ui.separator();
                ui.horizontal(|ui| {
                    ui.label("file");
                    ui.text_edit_singleline(&mut self.name);
                    let ok = match purpose {
                        BrowseFor::Open => "Open",
                        BrowseFor::Save => "Save",
                    };
                    if ui.button(ok).clicked() && !self.name.trim().is_empty() {
                        let p = PathBuf::from(self.name.trim());
                        chosen = Some(if p.is_absolute() { p } else { self.dir.join(p) });
                    }
                });
            });
        if !open {
            self.purpose = None;
        }
        if chosen.is_some() {
            self.purpose = None;
        }
        chosen.map(|p| (purpose, p))
    }
}

/// Watches one file's modification time.
pub struct Watch {
    /// The file watched.
    pub path: PathBuf,
    mtime: Option<SystemTime>,
    checked: Instant,
}

impl Watch {
    /// Starts watching `path` from its current state.
    pub fn new(path: PathBuf) -> Watch {
        let mtime = std::fs::metadata(&path).and_then(|m| m.modified()).ok();
        Watch {
            path,
            mtime,
            checked: Instant::now(),
        }
    }

    /// Whether the file changed since the last call that said so (checked at most every
    /// half second; a file that vanished is not a change until it comes back).
    pub fn changed(&mut self) -> bool {
        if self.checked.elapsed().as_millis() < 500 {
            return false;
        }
        self.force_changed()
    }

    /// [`Watch::changed`] without the half-second limit.
    pub fn force_changed(&mut self) -> bool {
        self.checked = Instant::now();
        let now = std::fs::metadata(&self.path)
            .and_then(|m| m.modified())
            .ok();
        if now.is_some() && now != self.mtime {
            self.mtime = now;
            return true;
        }
        false
    }

    /// Records the file as it is now (after the window saved it).
    pub fn touch(&mut self) {
        self.mtime = std::fs::metadata(&self.path)
            .and_then(|m| m.modified())
            .ok();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_watch_sees_a_rewrite_and_ignores_its_own_saves() {
        let dir = std::env::temp_dir().join(format!("fathom-watch-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("s.ron");
        std::fs::write(&p, "a").unwrap();
        let mut w = Watch::new(p.clone());
        assert!(!w.force_changed());
        // File systems keep modification times to a few ms at least; make sure it moves.
        std::thread::sleep(std::time::Duration::from_millis(20));
        std::fs::write(&p, "b").unwrap();
        let t = std::fs::metadata(&p).unwrap().modified().unwrap();
        let later = t + std::time::Duration::from_secs(1);
        std::fs::File::options()
            .write(true)
            .open(&p)
            .unwrap()
            .set_modified(later)
            .unwrap();
        assert!(w.force_changed());
        assert!(!w.force_changed());
        std::fs::remove_dir_all(&dir).ok();
    }
}
