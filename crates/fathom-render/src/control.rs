//! Cancellation and progress of a frame: a [`CancelToken`] a window sets when the camera has
//! moved on (the renderers check it between tiles), and a progress callback that a command
//! line drives its progress bar from.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Shared flag that abandons the frame being rendered. Clones share the flag.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token that is not cancelled.
    pub fn new() -> CancelToken {
        CancelToken::default()
    }

    /// Asks the frame being rendered to stop (from any thread).
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`CancelToken::cancel`] was called since the last [`CancelToken::reset`].
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Clears the flag for the next frame.
    pub fn reset(&self) {
        self.0.store(false, Ordering::Relaxed);
    }

    /// The flag itself, as the renderers take it.
    pub fn flag(&self) -> &AtomicBool {
        &self.0
    }
}

/// How far a frame has got: units (tiles, or passes) done out of the total.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Units finished.
    pub done: usize,
    /// Units in the frame.
    pub total: usize,
}

/// The cancellation and progress hooks of one render.
#[derive(Clone, Copy, Default)]
pub struct Control<'a> {
    /// Set to abandon the frame; `None` when it cannot be cancelled.
    pub cancel: Option<&'a CancelToken>,
    /// Called (from worker threads) as units finish.
    pub progress: Option<&'a (dyn Fn(Progress) + Sync)>,
}

impl Control<'_> {
    /// Whether the frame should stop now.
    pub fn cancelled(&self) -> bool {
        self.cancel.is_some_and(CancelToken::is_cancelled)
    }

    /// Reports progress.
    pub fn report(&self, done: usize, total: usize) {
        if let Some(p) = self.progress {
            p(Progress { done, total });
        }
    }
}
