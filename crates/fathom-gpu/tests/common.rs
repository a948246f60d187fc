//! Helpers shared by the GPU integration tests: the device (failing loudly without one) and a
//! small deterministic random generator.

use fathom_core::frame::Frame;
use fathom_gpu::{Gpu, Renderer};
use fathom_trace::post::to_rgb8;
use std::sync::{LazyLock, Mutex, MutexGuard};

static SHARED: LazyLock<Mutex<Renderer>> = LazyLock::new(|| Mutex::new(fresh_renderer()));

/// One renderer shared by the tests of a binary: lavapipe compiles each pipeline on its first
/// dispatch, which takes a minute or more on a loaded 2-core machine, so tests share it.
#[allow(dead_code)]
pub fn renderer() -> MutexGuard<'static, Renderer> {
    SHARED.lock().unwrap_or_else(|e| e.into_inner())
}

/// A renderer of its own on Vulkan (lavapipe on a machine without a GPU). Panics, never skips,
/// when no adapter is found: CI must fail rather than pass without testing the GPU path.
#[allow(dead_code)]
pub fn fresh_renderer() -> Renderer {
    let gpu = Gpu::headless_vulkan().unwrap_or_else(|e| {
        panic!("GPU tests need a Vulkan adapter: {e}\n(run scripts/setup.sh to install Mesa's lavapipe)")
    });
    Renderer::new(gpu).unwrap_or_else(|e| panic!("{e}"))
}

/// The seeded generator the tests draw parameters and points from.
#[allow(unused_imports)] // not every test binary draws random numbers
pub use fathom_core::rng::SplitMix64 as Rng;

/// Largest per-channel difference of the 8-bit sRGB output that counts as "the same colour".
#[allow(dead_code)]
pub const COLOUR_TOL: u8 = 8;

/// Whether pixel `i` lies on a silhouette of `f`: a 3x3 neighbour differs in hit/miss.
#[allow(dead_code)]
fn on_silhouette(f: &Frame, i: usize) -> bool {
    let (x, y) = ((i as u32 % f.width) as i64, (i as u32 / f.width) as i64);
    let hit = f.is_hit(i);
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (nx, ny) = (x + dx, y + dy);
            if nx < 0 || ny < 0 || nx >= f.width as i64 || ny >= f.height as i64 {
                continue;
            }
            if f.is_hit(f.index(nx as u32, ny as u32)) != hit {
                return true;
            }
        }
    }
    false
}

/// (fraction of pixels whose colours agree within [`COLOUR_TOL`], hit/miss disagreements away
/// from silhouettes, hit/miss disagreements on them).
#[allow(dead_code)]
pub fn compare(a: &Frame, b: &Frame) -> (f64, usize, usize) {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "frame sizes differ"
    );
    let (ca, cb) = (to_rgb8(a), to_rgb8(b));
    let mut same = 0;
    let mut hit_bad = 0;
    let mut hit_sil = 0;
    for i in 0..a.len() {
        let d = (0..3)
            .map(|c| ca[3 * i + c].abs_diff(cb[3 * i + c]))
            .max()
            .unwrap();
        if d <= COLOUR_TOL {
            same += 1;
        }
        if a.is_hit(i) != b.is_hit(i) {
            if on_silhouette(a, i) || on_silhouette(b, i) {
                hit_sil += 1;
            } else {
                hit_bad += 1;
            }
        }
    }
    (same as f64 / a.len() as f64, hit_bad, hit_sil)
}
