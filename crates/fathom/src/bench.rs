//! `fathom bench`: benchmarks that print JSON. Each kind lives in its own module.

use clap::{Args, Subcommand};

#[derive(Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    kind: BenchKind,
}

#[derive(Subcommand)]
enum BenchKind {
    /// Tape evaluations per second per thread for each preset (f64 scalar, f32 packet), and
    /// tape compile time for a 100-node tree.
    Eval(crate::bench_eval::EvalArgs),
    /// The explorer's render side at 1280x720: interactive frame time and the render scale it
    /// settles at, time from the camera stopping to full resolution, parameter-edit latency;
    /// on the CPU tracer and on the GPU renderer (lavapipe when there is no GPU).
    Explore(crate::bench_explore::ExploreBenchArgs),
    /// Render farm: an N-task local array against one process (overhead per task), and the
    /// time to resume after a failure.
    Farm(crate::bench_farm::FarmBenchArgs),
    /// GPU renderer vs CPU tracer per preset: ms per frame and evaluations per pixel.
    Gpu(crate::bench_gpu::GpuArgs),
    /// Live modulation: latency from an OSC packet to the frame that shows it, p99 frame time
    /// during an OSC flood against a quiet run, and fps of `fathom render --path`.
    Live(crate::bench_live::LiveBenchArgs),
    /// Microgeometry demos on the CPU and GPU renderers, and baked-grid error and memory.
    Micro(crate::bench_micro::MicroBenchArgs),
    /// Streaming mesher: triangles/s, peak RSS and surface error for Menger and Mandelbulb,
    /// sphere Hausdorff, and Mandelbulber2's mesh export where installed.
    Mesh(crate::bench_mesh::MeshBenchArgs),
    /// Path tracer: paths/s per preset at 640x480, time to 2 % RMSE against a high-spp
    /// reference (raw and denoised), and one explorer accumulation pass at 1280x720.
    Pathtrace(crate::bench_pathtrace::PathTraceBenchArgs),
    /// `fathom mesh --max-triangles`: triangles and STL bytes before and after simplification,
    /// the Hausdorff distance between the meshes, and the triangle estimate against the count.
    Simplify(crate::bench_simplify::SimplifyBenchArgs),
    /// The sparse voxel octree explorer's evaluation: writes a markdown report with plots.
    Svo(crate::bench_svo::SvoArgs),
    /// Renders every preset with basic, enhanced and enhanced+prepass tracing: wall ms, rays/s,
    /// distance evaluations per pixel.
    Trace(crate::bench_trace::TraceArgs),
    /// Volume path tracer paths/s on a Menger density (majorant grid vs one global majorant)
    /// and physarum agent-steps/s with 1M agents on 256^3.
    Volume(crate::bench_volume::VolumeBenchArgs),
    /// The explorer's real window under Xvfb with real X input (needs xvfb and xdotool):
    /// launch to first picture, fps while dragging, drag latency, per renderer.
    Window(crate::bench_window::WindowBenchArgs),
}

pub fn run(a: BenchArgs) -> Result<(), String> {
    match a.kind {
        BenchKind::Eval(e) => crate::bench_eval::run(e),
        BenchKind::Explore(e) => crate::bench_explore::run(e),
        BenchKind::Farm(f) => crate::bench_farm::run(f),
        BenchKind::Gpu(g) => crate::bench_gpu::run(g),
        BenchKind::Live(l) => crate::bench_live::run(l),
        BenchKind::Micro(m) => crate::bench_micro::run(m),
        BenchKind::Mesh(m) => crate::bench_mesh::run(m),
        BenchKind::Pathtrace(p) => crate::bench_pathtrace::run(p),
        BenchKind::Simplify(s) => crate::bench_simplify::run(s),
        BenchKind::Svo(s) => crate::bench_svo::run(s),
        BenchKind::Trace(t) => crate::bench_trace::run(t),
        BenchKind::Volume(v) => crate::bench_volume::run(v),
        BenchKind::Window(w) => crate::bench_window::run(w),
    }
}
