//! Undo and redo of scene edits: whole-scene snapshots (a scene is a few kilobytes), one per
//! gesture. A drag of a slider is one gesture however many frames it lasts: the window records
//! the scene as it was when the gesture began and nothing more until another widget is edited.

use fathom_core::Scene;

/// Most edits kept.
pub const MAX_UNDO: usize = 256;

/// The undo and redo stacks.
#[derive(Default)]
pub struct History {
    undo: Vec<(String, Scene)>,
    redo: Vec<(String, Scene)>,
}

impl History {
    /// Records that `label` changed the scene from `before`; clears the redo stack.
    pub fn record(&mut self, label: impl Into<String>, before: Scene) {
        self.undo.push((label.into(), before));
        if self.undo.len() > MAX_UNDO {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    /// The scene before the last edit (and `current` goes on the redo stack), if any.
    pub fn undo(&mut self, current: &Scene) -> Option<(String, Scene)> {
        let (label, before) = self.undo.pop()?;
        self.redo.push((label.clone(), current.clone()));
        Some((label, before))
    }

    /// The scene after the last undone edit, if any.
    pub fn redo(&mut self, current: &Scene) -> Option<(String, Scene)> {
        let (label, after) = self.redo.pop()?;
        self.undo.push((label.clone(), current.clone()));
        Some((label, after))
    }

    /// The label of the edit [`History::undo`] would undo.
    pub fn next_undo(&self) -> Option<&str> {
        self.undo.last().map(|(l, _)| l.as_str())
    }

    /// The label of the edit [`History::redo`] would redo.
    pub fn next_redo(&self) -> Option<&str> {
        self.redo.last().map(|(l, _)| l.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undo_and_redo_walk_the_edits_both_ways() {
        let a = fathom_core::scenes::sphere(1.0);
        let b = fathom_core::scenes::sphere(2.0);
        let c = fathom_core::scenes::sphere(3.0);
        let mut h = History::default();
        h.record("radius 2", a.clone());
        h.record("radius 3", b.clone());
        assert_eq!(h.next_undo(), Some("radius 3"));
        let (_, s) = h.undo(&c).unwrap();
        assert_eq!(s, b);
        let (_, s) = h.undo(&s).unwrap();
        assert_eq!(s, a);
        assert!(h.undo(&s).is_none());
        let (_, s) = h.redo(&a).unwrap();
        assert_eq!(s, b);
        // A new edit drops what could be redone.
        h.record("other", s);
        assert!(h.redo(&c).is_none());
        for _ in 0..MAX_UNDO + 10 {
            h.record("x", a.clone());
        }
        assert_eq!(h.undo.len(), MAX_UNDO);
    }
}
