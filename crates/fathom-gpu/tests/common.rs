//! Helpers shared by the GPU integration tests: the device (failing loudly without one) and a
//! small deterministic random generator.

use fathom_gpu::{Gpu, Renderer};
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

/// SplitMix64: deterministic and dependency-free.
#[allow(dead_code)] // not every test binary draws random numbers
pub struct Rng(pub u64);

#[allow(dead_code)]
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}
