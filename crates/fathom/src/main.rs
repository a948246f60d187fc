//! The `fathom` command: render, list, print scenes, benchmark.
//!
//! Each subcommand lives in its own module; this file only parses the command line and
//! dispatches. The modules are thin: they turn flags into a `fathom_render::RenderRequest` (or
//! a zoom), call the render layer's session, and write files.
//! Run with no arguments it opens the explorer window when a display is present, and otherwise
//! renders the default preset and says where it went.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod args;
mod bench;
mod bench_eval;
mod bench_explore;
mod bench_farm;
mod bench_gpu;
mod bench_live;
mod bench_mesh;
mod bench_micro;
mod bench_pathtrace;
mod bench_simplify;
mod bench_svo;
mod bench_trace;
mod bench_volume;
mod bench_window;
mod cmd_explore;
mod cmd_farm;
mod cmd_flight;
mod cmd_import;
mod cmd_list;
mod cmd_mesh;
mod cmd_micro;
mod cmd_osc;
mod cmd_render;
mod cmd_scene;
mod cmd_volume;
mod cmd_zoom;

/// Explore infinite 3D worlds built from distance fields: fractals, CSG trees folded into
/// iterated function systems, rendered by sphere tracing.
///
/// Examples:
///   fathom                                   open the explorer window (with a display), or
///                                            render the default preset to fathom.png
///   fathom explore --preset menger           fly through a preset and edit it live
///   fathom render --preset menger -o m.png   render a preset
///   fathom list primitives                   what a scene can be made of
///   fathom scene --preset mandelbulb > my.ron   start a scene file from a preset
///   fathom render my.ron -o my.png           render it
#[derive(Parser)]
#[command(name = "fathom", version, verbatim_doc_comment)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    // Render and Zoom take their help (summary, then examples) from their argument structs; a
    // doc comment here would replace it.
    Render(Box<cmd_render::RenderArgs>),
    /// List presets, primitives, operators or fractals with their parameters.
    List(cmd_list::ListArgs),
    /// Print a preset (or a scene file, normalised) as scene-file text.
    Scene(cmd_scene::SceneArgs),
    Zoom(cmd_zoom::ZoomArgs),
    Micro(Box<cmd_micro::MicroArgs>),
    Mesh(Box<cmd_mesh::MeshArgs>),
    Import(cmd_import::ImportArgs),
    Explore(cmd_explore::ExploreArgs),
    /// Run a benchmark and print JSON.
    Bench(bench::BenchArgs),
    Volume(Box<cmd_volume::VolumeArgs>),
    OscSend(cmd_osc::OscSendArgs),
    OscMonitor(cmd_osc::OscMonitorArgs),
    Farm(cmd_farm::FarmArgs),
}

/// The arguments of a command given no flags, from its clap declarations (every flag has a
/// default): code that builds arguments states only what differs, so a new flag needs no
/// second default.
pub fn clap_defaults<T: clap::Args + clap::FromArgMatches>() -> T {
    let cmd = T::augment_args(clap::Command::new("fathom"));
    let m = cmd
        .try_get_matches_from(["fathom"])
        .expect("every flag has a default");
    T::from_arg_matches(&m).expect("every flag has a default")
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Ctrl-C, SIGTERM or SIGHUP: remove every temporary file (half-written outputs, mesh
    // spools) and exit 130, so an interrupted command leaves its outputs as they were. The
    // explorer window keeps its own handling of the terminal.
    if !matches!(cli.command, Some(Command::Explore(_)))
        && let Err(e) = ctrlc::set_handler(|| fathom_core::cleanup::interrupted())
    {
        eprintln!(
            "fathom: warning: no Ctrl-C handler ({e}); an interrupted run may leave temporary files"
        );
    }
    let result = match cli.command {
        None => cmd_explore::run_without_arguments(),
        Some(Command::Render(a)) => render(*a),
        Some(Command::List(a)) => cmd_list::run(a),
        Some(Command::Scene(a)) => cmd_scene::run(a),
        Some(Command::Zoom(a)) => zoom(a),
        Some(Command::Micro(a)) => cmd_micro::run(*a),
        Some(Command::Mesh(a)) => cmd_mesh::run(*a),
        Some(Command::Import(a)) => cmd_import::run(a),
        Some(Command::Explore(a)) => cmd_explore::run(a),
        Some(Command::Bench(a)) => bench::run(a),
        Some(Command::Volume(a)) => cmd_volume::run(*a),
        Some(Command::OscSend(a)) => cmd_osc::send(a),
        Some(Command::OscMonitor(a)) => cmd_osc::monitor(a),
        Some(Command::Farm(a)) => cmd_farm::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fathom: error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `fathom render`: a farm shard (`--shard`, `--tiles`), a flight path's frames (`--path`)
/// or one image. The size of a `.fract` scene is Mandelbulber's unless `--size` is given.
fn render(mut a: cmd_render::RenderArgs) -> Result<(), String> {
    cmd_render::size_from_fract(&mut a)?;
    if a.shard.is_some() || a.tiles.is_some() {
        cmd_farm::render_shard(&a)
    } else if a.path.is_some() {
        let scene = cmd_render::load_scene(&a)?;
        cmd_flight::run(&a, scene)
    } else {
        cmd_render::run(a)
    }
}

/// `fathom zoom`: a farm shard (`--shard`) or the whole zoom here.
fn zoom(a: cmd_zoom::ZoomArgs) -> Result<(), String> {
    if a.shard.is_some() {
        cmd_farm::zoom_shard(&a)
    } else {
        cmd_zoom::run(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn every_command_help_teaches_by_example() {
        let mut cli = Cli::command();
        cli.build();
        for name in [
            "render",
            "zoom",
            "explore",
            "list",
            "scene",
            "volume",
            "micro",
            "mesh",
            "import",
            "osc-send",
            "osc-monitor",
            "farm",
        ] {
            let sub = cli.find_subcommand_mut(name).unwrap();
            let help = sub.render_long_help().to_string();
            let example = format!("\n  fathom {name} ");
            assert!(
                help.contains(&example),
                "{name} --help has no example:\n{help}"
            );
        }
        cli.debug_assert();
    }
}
