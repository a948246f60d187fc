//! Every example command the project shows, run as written and checked for what it promises.
//!
//! The examples are read from where users read them: the ```sh blocks of README.md
//! (`cargo run --release -- ARGS` is `fathom ARGS`) and the `Examples:` sections of
//! `fathom --help` and of every subcommand's `--help` (nested ones too). Each example's
//! command text (up to its comment: `#`, two spaces or a `(`) must have exactly one entry in
//! [`CASES`], and every entry must still be an example: a new example without a check fails
//! `every_example_has_exactly_one_entry`, a removed one leaves a stale entry that fails it too.
//!
//! An entry either runs the command or names why it cannot run here ([`Run::Exception`]).
//! Run entries execute in order in one scratch directory (so `fathom scene ... > my.ron` makes
//! the `my.ron` later examples use; `docs/` and `crates/` are linked in), with the display variables removed.
//! Large examples run at reduced size, the documented way: the entry's `rewrite` list replaces
//! size flags in the command text (`--grid 256` -> `--grid 48`, `--size 8192x8192` ->
//! `--size 128x128`, ...), and `extra` appends flags (a small `--size` where the example uses
//! the default); the rest of the command is as written. Each output is then checked
//! ([`Expect`]): images open, have the promised size and are not one colour; meshes, grids,
//! JSON and scene files are what their extension says and not empty.
//!
//! Placeholder inputs the examples name (`mandelbox001.fract`, `my.obj`, `leaves.ron`, ...)
//! are made by [`SETUP`] first, each from the project's own commands or the files
//! scripts/setup.sh installs (Mandelbulber2's examples).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What a run example must leave behind.
#[derive(Clone, Copy, Debug)]
enum Expect {
    /// A PNG or EXR image of this size (0 = any) with structure (not one colour).
    Image(&'static str, u32, u32),
    /// A directory holding at least `n` images with this extension, the first with structure.
    Images(&'static str, &'static str, usize),
    /// A mesh file (format by extension) with at least one triangle.
    Mesh(&'static str),
    /// A directory holding at least `n` meshes with this extension.
    Meshes(&'static str, &'static str, usize),
    /// A JSON file (`-` for standard output).
    Json(&'static str),
    /// A scene file that `fathom scene FILE --check` accepts.
    Scene(&'static str),
    /// A Mitsuba 3 `.vol` grid.
    Vol(&'static str),
    /// A file that exists and is not empty.
    File(&'static str),
    /// Standard output (or error) contains this text.
    Says(&'static str),
}

/// How an example is covered.
#[derive(Clone, Copy, Debug)]
enum Run {
    /// Runs the command with `rewrite` applied to its text and `extra` appended, then checks.
    Check {
        /// Command lines run first (inputs this example needs that no earlier one made).
        pre: &'static [&'static str],
        rewrite: &'static [(&'static str, &'static str)],
        extra: &'static [&'static str],
        expect: &'static [Expect],
    },
    /// Not run here, and why (where it is covered instead).
    Exception(&'static str),
}

use Expect::*;

/// One example and how it is covered.
struct Case {
    cmd: &'static str,
    run: Run,
}

const fn check(
    cmd: &'static str,
    rewrite: &'static [(&'static str, &'static str)],
    extra: &'static [&'static str],
    expect: &'static [Expect],
) -> Case {
    Case {
        cmd,
        run: Run::Check {
            pre: &[],
            rewrite,
            extra,
            expect,
        },
    }
}

const fn check_after(
    pre: &'static [&'static str],
    cmd: &'static str,
    rewrite: &'static [(&'static str, &'static str)],
    extra: &'static [&'static str],
    expect: &'static [Expect],
) -> Case {
    Case {
        cmd,
        run: Run::Check {
            pre,
            rewrite,
            extra,
            expect,
        },
    }
}

const fn except(cmd: &'static str, why: &'static str) -> Case {
    Case {
        cmd,
        run: Run::Exception(why),
    }
}

/// Inputs the examples name, made before them (same syntax as a case's command).
const SETUP: &[(&str, &str)] = &[
    (
        "fathom scene --preset menger > my-scene.ron",
        "my-scene.ron",
    ),
    ("fathom scene --preset menger > leaves.ron", "leaves.ron"),
    (
        "cp crates/fathom-micro/demos/bush-leaves.ron other.ron",
        "other.ron",
    ),
    (
        "fathom mesh --preset menger -o my.obj --resolution 8 --method mc",
        "my.obj",
    ),
    ("cp docs/examples/mandelbulb-dive.ron dive.ron", "dive.ron"),
    (
        "cp /usr/share/mandelbulber2/examples/mandelbox001.fract mandelbox001.fract",
        "mandelbox001.fract",
    ),
    (
        "fathom volume --preset menger --grid 24 --export cloud.vol",
        "cloud.vol",
    ),
];

const SMALL: &[&str] = &["--size", "96x64"];

/// The check table: one entry per distinct example command, in the order they run.
const CASES: &[Case] = &[
    // README.md
    check(
        "fathom",
        &[],
        &[],
        &[Image("fathom.png", 0, 0), Says("fathom.png")],
    ),
    except("scripts/test.sh", "it is CI itself (it runs this test)"),
    check("fathom --help", &[], &[], &[Says("Examples:")]),
    check("fathom list presets", &[], &[], &[Says("menger")]),
    check(
        "fathom scene --preset menger > my.ron",
        &[],
        &[],
        &[Scene("my.ron")],
    ),
    check(
        "fathom render my.ron -o my.png --size 1280x720",
        &[("--size 1280x720", "--size 128x72")],
        &[],
        &[Image("my.png", 128, 72)],
    ),
    check(
        "fathom render --preset menger --gpu",
        &[],
        &[],
        &[Image("fathom.png", 0, 0)],
    ),
    check(
        "fathom render docs/examples/materials.ron --integrator path --spp 128 --denoise -o lit.png",
        &[("--spp 128", "--spp 4")],
        SMALL,
        &[Image("lit.png", 96, 64), Says("spp")],
    ),
    check(
        "fathom render --preset mandelbulb --stereo ods --size 2048x1024 -o vr.png",
        &[("--size 2048x1024", "--size 128x64")],
        &[],
        &[Image("vr.png", 128, 128)],
    ),
    check(
        "fathom zoom --preset menger --depth 1e11 --frames 300 --stats zoom.json",
        &[("--frames 300", "--frames 4")],
        SMALL,
        &[Json("zoom.json")],
    ),
    check(
        "fathom bench eval",
        &[],
        &["--seconds", "0.05"],
        &[Json("-")],
    ),
    check(
        "fathom volume --sim physarum --preset tendrils --grid 256 --spp 64 -o slime.png",
        &[("--grid 256", "--grid 64"), ("--spp 64", "--spp 8")],
        &["--size", "96x96"],
        &[Image("slime.png", 96, 96)],
    ),
    check(
        "fathom volume --preset menger --grid 128 --export menger.vol",
        &[("--grid 128", "--grid 24")],
        &[],
        &[Vol("menger.vol")],
    ),
    check(
        "fathom micro --demo teapot -o teapot.png",
        &[],
        SMALL,
        &[Image("teapot.png", 96, 64)],
    ),
    check(
        "fathom render docs/examples/mandelbulb-dive.ron --path dive --frames 300 -o dive/",
        &[("--frames 300", "--frames 3")],
        SMALL,
        &[Images("dive", "png", 3)],
    ),
    check(
        "fathom render --preset mandelbulb -o layers.exr",
        &[],
        SMALL,
        &[Image("layers.exr", 96, 64)],
    ),
    check(
        "fathom mesh --preset menger -o menger.stl --resolution 192",
        &[("--resolution 192", "--resolution 32")],
        &[],
        &[Mesh("menger.stl"), Says("estimate: about")],
    ),
    check(
        "fathom import /usr/share/mandelbulber2/examples/mandelbulb001.fract > bulb.ron",
        &[],
        &[],
        &[Scene("bulb.ron")],
    ),
    check(
        "fathom farm slurm --preset menger --size 8192x8192 --tiles 64 -o poster/ --submit",
        &[
            ("--size 8192x8192", "--size 128x128"),
            ("--tiles 64", "--tiles 16"),
            (" --submit", ""),
        ],
        &[],
        &[File("poster/farm.sbatch"), File("poster/farm.json")],
    ),
    // fathom --help
    check(
        "fathom explore --preset menger",
        &[("fathom explore", "xvfb-run -a fathom explore")],
        &["--frames", "3"],
        &[],
    ),
    check(
        "fathom render --preset menger -o m.png",
        &[],
        SMALL,
        &[Image("m.png", 96, 64)],
    ),
    check("fathom list primitives", &[], &[], &[Says("sphere")]),
    check(
        "fathom scene --preset mandelbulb > my.ron",
        &[],
        &[],
        &[Scene("my.ron")],
    ),
    check(
        "fathom render my.ron -o my.png",
        &[],
        SMALL,
        &[Image("my.png", 96, 64)],
    ),
    // fathom explore --help: the window under Xvfb (scripts/setup.sh installs xvfb-run), each
    // for a few frames (--frames N closes it after N frames).
    check(
        "fathom explore --preset mandelbulb",
        &[("fathom explore", "xvfb-run -a fathom explore")],
        &["--frames", "3"],
        &[],
    ),
    check(
        "fathom explore my.ron",
        &[("fathom explore", "xvfb-run -a fathom explore")],
        &["--frames", "3"],
        &[],
    ),
    check(
        "fathom explore --preset menger --renderer svo",
        &[("fathom explore", "xvfb-run -a fathom explore")],
        &["--frames", "3"],
        &[],
    ),
    check(
        "fathom explore --preset menger --frames 60 --screenshot shot.png --log frames.jsonl",
        &[
            ("fathom explore", "xvfb-run -a fathom explore"),
            ("--frames 60", "--frames 5"),
        ],
        &[],
        &[Image("shot.png", 0, 0), File("frames.jsonl")],
    ),
    check(
        "fathom explore docs/examples/mandelbulb-dive.ron --osc-port 9000",
        &[
            ("fathom explore", "xvfb-run -a fathom explore"),
            ("--osc-port 9000", "--osc-port 19731"),
        ],
        &["--frames", "3"],
        &[],
    ),
    // fathom render --help
    check(
        "fathom render --preset mandelbulb -o bulb.png",
        &[],
        SMALL,
        &[Image("bulb.png", 96, 64)],
    ),
    check(
        "fathom render my.ron -o my.png --size 1920x1080 --supersample 2",
        &[("--size 1920x1080", "--size 96x54")],
        &[],
        &[Image("my.png", 96, 54)],
    ),
    check(
        "fathom render --preset mandelbulb --eye 0,0,2 --fov 30 -o close.png",
        &[],
        SMALL,
        &[Image("close.png", 96, 64)],
    ),
    check(
        "fathom render --preset mandelbulb -o b.png --steps steps.png --stats stats.json",
        &[],
        SMALL,
        &[
            Image("b.png", 96, 64),
            Image("steps.png", 96, 64),
            Json("stats.json"),
        ],
    ),
    check(
        "fathom render --preset mandelbulb --gpu -o gpu.png",
        &[],
        SMALL,
        &[Image("gpu.png", 96, 64)],
    ),
    check(
        "fathom render --preset mandelbulb --gpu --stereo ods --size 2048x1024 -o vr.png",
        &[("--size 2048x1024", "--size 128x64")],
        &[],
        &[Image("vr.png", 128, 128)],
    ),
    check(
        "fathom render --preset menger --stereo sbs --size 640x480 -o pair.png",
        &[("--size 640x480", "--size 64x48")],
        &[],
        &[Image("pair.png", 128, 48)],
    ),
    check(
        "fathom render --preset mandelbulb --bit-depth 16 -o deep.png",
        &[],
        SMALL,
        &[Image("deep.png", 96, 64)],
    ),
    check(
        "fathom render --preset menger --integrator path --spp 256 --denoise -o lit.png",
        &[("--spp 256", "--spp 4")],
        SMALL,
        &[Image("lit.png", 96, 64)],
    ),
    check(
        "fathom render --preset mandelbulb --integrator path --time-limit 30s --aperture 0.02 -o dof.png",
        &[("--time-limit 30s", "--time-limit 1s")],
        SMALL,
        &[Image("dof.png", 96, 64)],
    ),
    check(
        "fathom render docs/examples/mandelbulb-dive.ron --path dive --frames 300 -o shots/dive-####.exr --camera-path shots/dive.glb",
        &[("--frames 300", "--frames 3")],
        SMALL,
        // The dive widens its field of view at the end: the camera path animates it too.
        &[
            Images("shots", "exr", 3),
            File("shots/dive.glb"),
            Says("KHR_animation_pointer"),
        ],
    ),
    check(
        "fathom render --preset menger --size 8192x8192 --tiles 64 --shard 3/64 -o poster/",
        // poster/ is the farm job below; the shard's tiles go beside it.
        &[
            ("--size 8192x8192", "--size 128x128"),
            ("--tiles 64", "--tiles 4"),
            ("--shard 3/64", "--shard 1/4"),
            ("-o poster/", "-o poster-shard/"),
        ],
        &[],
        &[Images("poster-shard", "png", 1)],
    ),
    check(
        "fathom render docs/examples/mandelbulb-dive.ron --path dive --frames 300 --shard 0/8 -o dive/",
        &[
            ("--frames 300", "--frames 8"),
            ("-o dive/", "-o dive-shard/"),
        ],
        SMALL,
        &[Images("dive-shard", "png", 1)],
    ),
    // fathom zoom --help
    check(
        "fathom zoom --preset menger --depth 1e15 --frames 450 -o deep/",
        &[("--frames 450", "--frames 3")],
        SMALL,
        &[Images("deep", "png", 3)],
    ),
    check(
        "fathom zoom --preset sierpinski --pixel 320,160 --depth 1e9 -o frames/",
        &[],
        &["--frames", "3"],
        &[Images("frames", "png", 3)],
    ),
    check(
        "fathom zoom my-scene.ron --toward 0.3,0.2,1 --depth 1e8 --stats z.json",
        &[],
        &["--size", "96x64", "--frames", "3"],
        &[Json("z.json")],
    ),
    check(
        "fathom zoom --preset mandelbulb --compare-every 10 --stats z.json",
        &[],
        &["--size", "96x64", "--frames", "11"],
        &[Json("z.json")],
    ),
    check(
        "fathom zoom --preset mandelbulb --compare-every 50 --compare-images cmp/",
        &[("--compare-every 50", "--compare-every 2")],
        &["--size", "96x64", "--frames", "3"],
        &[Images("cmp", "png", 1)],
    ),
    check(
        "fathom zoom --preset mandelbulb --frames 600 -o frames/",
        &[
            ("--frames 600", "--frames 3"),
            ("-o frames/", "-o bulb-frames/"),
        ],
        SMALL,
        &[Images("bulb-frames", "png", 3)],
    ),
    check(
        "fathom zoom --preset menger --traversal kdrestart --stats kd.json",
        &[],
        &["--size", "96x64", "--frames", "3"],
        &[Json("kd.json")],
    ),
    check(
        "fathom zoom --preset menger-tour --frames 900 --size 1280x720 -o tour/",
        &[
            ("--frames 900", "--frames 3"),
            ("--size 1280x720", "--size 96x54"),
        ],
        &[],
        &[Images("tour", "png", 3)],
    ),
    check(
        "fathom zoom --preset menger --depth 1e6 --frames 240 --shard 2/8 -o zoom/",
        &[("--frames 240", "--frames 16")],
        SMALL,
        &[Images("zoom", "png", 2)],
    ),
    // fathom list --help, fathom scene --help
    check("fathom list operators", &[], &[], &[Says("scale")]),
    check(
        "fathom list all --json > registry.json",
        &[],
        &[],
        &[Json("registry.json")],
    ),
    check(
        "fathom scene --preset menger > menger.ron",
        &[],
        &[],
        &[Scene("menger.ron")],
    ),
    check("fathom scene my.ron", &[], &[], &[Says("root")]),
    check("fathom scene my.ron --check", &[], &[], &[]),
    check("fathom scene --list", &[], &[], &[Says("mandelbulb")]),
    // fathom volume --help
    check(
        "fathom volume --sim physarum --preset tendrils --steps 300 --grid 256 -o out.png --spp 64",
        &[
            ("--steps 300", "--steps 150"),
            ("--grid 256", "--grid 64"),
            ("--spp 64", "--spp 8"),
        ],
        &["--size", "96x96"],
        &[Image("out.png", 96, 96)],
    ),
    check(
        "fathom volume --sim physarum --preset lattice --grid 128 --export lattice.vol",
        &[("--grid 128", "--grid 32")],
        &["--steps", "60"],
        &[Vol("lattice.vol")],
    ),
    check(
        "fathom volume --grid cloud.vol --density-scale 30 --albedo 0.9 --g 0.6 --env 1 --eye 2,1.5,2.5 --target 0.5,0.5,0.5 --fov 35 --size 512x512 --spp 128 -o cloud.exr",
        &[("--size 512x512", "--size 64x64"), ("--spp 128", "--spp 8")],
        &[],
        &[Image("cloud.exr", 64, 64)],
    ),
    check(
        "fathom volume --preset menger --grid 128 --density-scale 20 -o sponge.png --stats sponge.json",
        &[("--grid 128", "--grid 32")],
        &["--size", "96x64", "--spp", "8"],
        &[Image("sponge.png", 96, 64), Json("sponge.json")],
    ),
    check(
        "fathom volume --scene my.ron --grid 192 --smooth 1.5 --sun 0.4,1,0.3 --sky-top 0.3,0.45,0.8 --sky-bottom 0.1,0.1,0.1 -o my.png",
        &[("--grid 192", "--grid 32")],
        &["--size", "96x64", "--spp", "8"],
        &[Image("my.png", 96, 64)],
    ),
    check(
        "fathom volume --sim physarum --preset cage --emission 4 --env 0 -o glow.png",
        &[],
        &[
            "--grid", "64", "--steps", "100", "--size", "96x96", "--spp", "8",
        ],
        &[Image("glow.png", 96, 96)],
    ),
    check(
        "fathom volume --preset menger --eye 0.1,0.2,0.3 --target 1,0,0 -o inside.png",
        &[],
        &["--grid", "32", "--size", "96x64", "--spp", "8"],
        &[Image("inside.png", 96, 64)],
    ),
    // fathom micro --help
    check(
        "fathom micro --demo bush --size 1920x1080 -o bush.png",
        &[("--size 1920x1080", "--size 96x54")],
        &[],
        &[Image("bush.png", 96, 54)],
    ),
    check(
        "fathom micro teapot --preset menger --shell 0.05 -o t.png",
        &[],
        SMALL,
        &[Image("t.png", 96, 64)],
    ),
    check(
        "fathom micro my.obj --texture leaves.ron --shell 0.02 --uv box -o my.png",
        &[],
        SMALL,
        &[Image("my.png", 96, 64)],
    ),
    check(
        "fathom micro --demo teapot --gpu -o gpu.png",
        &[],
        SMALL,
        &[Image("gpu.png", 96, 64)],
    ),
    check(
        "fathom micro --demo teapot --bake 128 --stats stats.json -o baked.png",
        &[("--bake 128", "--bake 32")],
        SMALL,
        &[Image("baked.png", 96, 64), Json("stats.json")],
    ),
    check(
        "fathom micro --cloud fern -o fern.png",
        &[],
        SMALL,
        &[Image("fern.png", 96, 64)],
    ),
    check(
        "fathom micro --cloud fern --fov 8 --target 0.1,0.3,0 -o zoom.png",
        &[],
        SMALL,
        &[Image("zoom.png", 96, 64)],
    ),
    check(
        "fathom micro bush --cloud fern --shell 0.15 -o ferns.png",
        &[],
        SMALL,
        &[Image("ferns.png", 96, 64)],
    ),
    check(
        "fathom micro --demo bush --texture-to other.ron --time 1.5 -o frame.png",
        &[],
        SMALL,
        &[Image("frame.png", 96, 64)],
    ),
    // fathom mesh --help
    check(
        "fathom mesh --preset mandelbulb -o bulb.ply --resolution 1024 --max-memory 2G --yes",
        &[("--resolution 1024", "--resolution 48")],
        &[],
        &[Mesh("bulb.ply")],
    ),
    check(
        "fathom mesh my.ron -o my.glb --bounds -1,-1,-1,1,1,1 --method mc",
        &[],
        &["--resolution", "32"],
        &[Mesh("my.glb")],
    ),
    check(
        "fathom mesh FILE.fract -o imported.obj --resolution 256",
        &[
            ("FILE.fract", "mandelbox001.fract"),
            ("--resolution 256", "--resolution 32"),
        ],
        &[],
        &[Mesh("imported.obj")],
    ),
    check(
        "fathom mesh docs/examples/mandelbulb-dive.ron --path dive --frames 48 -o dive-meshes/",
        &[("--frames 48", "--frames 2")],
        &["--resolution", "24"],
        &[Meshes("dive-meshes", "ply", 2)],
    ),
    // fathom import --help
    check(
        "fathom import mandelbox001.fract > box.ron",
        &[],
        &[],
        &[Scene("box.ron")],
    ),
    check(
        "fathom import /usr/share/mandelbulber2/examples/mandelbulb001.fract -o bulb.ron",
        &[],
        &[],
        &[Scene("bulb.ron")],
    ),
    check(
        "fathom render mandelbox001.fract -o box.png",
        &[],
        SMALL,
        &[Image("box.png", 96, 64)],
    ),
    // fathom osc-send --help, fathom osc-monitor --help: UDP to a port nobody listens on is
    // sent all the same.
    check("fathom osc-send /fathom/light 0.8", &[], &[], &[]),
    check(
        "fathom osc-send /muse/elements/alpha_absolute 0.4 0.5 0.45 0.38 --to 127.0.0.1:5000",
        &[],
        &[],
        &[],
    ),
    check(
        "fathom osc-send /fathom/light 0.2 --repeat 100 --interval-ms 50",
        &[("--repeat 100", "--repeat 3")],
        &[],
        &[],
    ),
    check("fathom osc-send /fathom/light nan", &[], &[], &[]),
    check(
        "fathom osc-monitor docs/examples/mandelbulb-dive.ron",
        &[],
        &["--seconds", "1"],
        &[],
    ),
    check_after(
        // my.ron is the mandelbulb preset above, which has no bindings; the example means a
        // scene with bindings (docs/live.md), such as the dive.
        &["cp docs/examples/mandelbulb-dive.ron my.ron"],
        "fathom osc-monitor my.ron --osc-bind 0.0.0.0:12345 --seconds 30",
        &[("--seconds 30", "--seconds 1")],
        &[],
        &[],
    ),
    // fathom farm --help: the Slurm submission itself is scripts/farm-slurm-test.sh's (it
    // starts a one-node cluster); here the job directory is made without --submit and rendered
    // by the local array.
    check(
        "fathom farm slurm dive.ron --path dive --frames 2400 -o dive/ --tasks 100 --partition gpu",
        &[
            ("--frames 2400", "--frames 4"),
            ("--tasks 100", "--tasks 2"),
            ("-o dive/", "-o dive-job/"),
        ],
        SMALL,
        &[File("dive-job/farm.sbatch")],
    ),
    except(
        "fathom farm slurm dive.ron --path dive --frames 2400 -o dive/ --tasks 100 --submit --wait",
        "--submit --wait needs a running Slurm cluster: scripts/farm-slurm-test.sh (run by scripts/test.sh after cargo test) starts one and submits and waits for a job the same way; the job directory this makes is checked by the --partition example above",
    ),
    check("fathom farm status poster/", &[], &[], &[Says("16 units")]),
    check("fathom farm work poster/ --shard 3/8", &[], &[], &[]),
    check("fathom farm work poster/", &[], &[], &[]),
    check("fathom farm run poster/ --tasks 8", &[], &[], &[]),
    check(
        "fathom farm run poster/ --tasks 8 --parallel 2",
        &[],
        &[],
        &[],
    ),
    check("fathom farm status poster/ --json", &[], &[], &[Json("-")]),
    check(
        "fathom farm assemble poster/ -o poster.png",
        &[],
        &[],
        &[Image("poster.png", 128, 128)],
    ),
    check_after(
        &["fathom farm run dive-job/ --tasks 2"],
        "fathom farm assemble dive/ -o dive.mp4 --fps 30",
        &[("dive/", "dive-job/")],
        &[],
        &[File("dive.mp4")],
    ),
    except(
        "fathom farm work DIR --shard $JOB_COMPLETION_INDEX/N",
        "a template for Kubernetes indexed jobs: DIR and N are placeholders and the index comes from the job's environment; `fathom farm work poster/ --shard 3/8` above runs the same code",
    ),
    except(
        "fathom farm work DIR --shard $AWS_BATCH_JOB_ARRAY_INDEX/N",
        "a template for AWS Batch arrays: DIR and N are placeholders and the index comes from the job's environment; `fathom farm work poster/ --shard 3/8` above runs the same code",
    ),
];

/// The examples of README.md's ```sh blocks, as `fathom ...` (or the script) commands.
fn readme_examples(root: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(root.join("README.md")).expect("README.md");
    let mut out = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            inside = line.trim() == "```sh";
            continue;
        }
        if !inside {
            continue;
        }
        let cmd = command_of(line);
        if cmd.is_empty() {
            continue;
        }
        let cmd = if let Some(rest) = cmd.strip_prefix("cargo run --release --") {
            format!("fathom{rest}")
        } else if cmd == "cargo run --release" {
            "fathom".to_string()
        } else {
            cmd
        };
        out.push(cmd);
    }
    out
}

/// The command part of an example line: up to a `#` comment, a run of two spaces or a `(`
/// comment.
fn command_of(line: &str) -> String {
    let mut end = line.len();
    for pat in [" #", "  ", " ("] {
        if let Some(i) = line.trim().find(pat) {
            end = end.min(i);
        }
    }
    let t = line.trim();
    t[..end.min(t.len())].trim().to_string()
}

fn fathom() -> &'static str {
    env!("CARGO_BIN_EXE_fathom")
}

fn help(path: &[&str]) -> String {
    let out = Command::new(fathom())
        .args(path)
        .arg("--help")
        .env("COLUMNS", "1000")
        .output()
        .expect("run fathom --help");
    assert!(out.status.success(), "fathom {path:?} --help failed");
    String::from_utf8(out.stdout).expect("UTF-8 help")
}

/// Subcommand names listed in a help text's `Commands:` section.
fn subcommands(help: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in help.lines() {
        if line.starts_with("Commands:") {
            inside = true;
            continue;
        }
        if inside {
            if !line.starts_with("  ") {
                break;
            }
            let name = line.split_whitespace().next().unwrap_or("");
            if !name.is_empty()
                && name != "help"
                && line.starts_with("  ")
                && !line.starts_with("   ")
            {
                out.push(name.to_string());
            }
        }
    }
    out
}

/// The example lines of every `--help`, top level and nested, as commands.
fn help_examples() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut queue: Vec<Vec<String>> = vec![vec![]];
    while let Some(path) = queue.pop() {
        let refs: Vec<&str> = path.iter().map(String::as_str).collect();
        let text = help(&refs);
        let mut inside = false;
        // A line ending in `\` continues on the next.
        let mut lines: Vec<String> = Vec::new();
        for l in text.lines() {
            match lines.last_mut() {
                Some(prev) if prev.ends_with('\\') => {
                    prev.pop();
                    prev.push_str(l.trim());
                }
                _ => lines.push(l.to_string()),
            }
        }
        for line in &lines {
            if line.trim_end().ends_with("Examples:") {
                inside = true;
                continue;
            }
            if inside && line.trim().is_empty() {
                inside = false;
            }
            if inside && line.trim_start().starts_with("fathom") {
                let cmd = command_of(line);
                out.push((format!("fathom {} --help", refs.join(" ")), cmd));
            }
        }
        for sub in subcommands(&text) {
            let mut p = path.clone();
            p.push(sub);
            queue.push(p);
        }
    }
    out
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn every_example_has_exactly_one_entry() {
    let mut examples: Vec<(String, String)> = readme_examples(&root())
        .into_iter()
        .map(|c| ("README.md".to_string(), c))
        .collect();
    examples.extend(help_examples());
    assert!(
        examples.len() > 50,
        "found only {} examples",
        examples.len()
    );
    let mut problems = Vec::new();
    for (wher, cmd) in &examples {
        let n = CASES.iter().filter(|c| c.cmd == cmd).count();
        if n != 1 {
            problems.push(format!(
                "{wher}: `{cmd}` has {n} entries in CASES (tests/examples.rs); add one that runs and checks it, or an exception with the reason"
            ));
        }
    }
    for c in CASES {
        if !examples.iter().any(|(_, e)| e == c.cmd) {
            problems.push(format!("CASES entry `{}` is no longer an example", c.cmd));
        }
        if let Run::Exception(why) = c.run {
            assert!(why.len() > 10, "`{}`: an exception needs its reason", c.cmd);
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The scratch directory the examples run in, with `docs/` linked.
fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!("fathom-examples-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    for sub in ["docs", "crates"] {
        std::os::unix::fs::symlink(root().join(sub).canonicalize().unwrap(), d.join(sub)).unwrap();
    }
    d
}

/// Longest a reduced example may take.
const TIMEOUT: Duration = Duration::from_secs(240);

/// Runs one command line (`fathom ...` or `cp ...`, with an optional `> FILE`) in `dir`;
/// returns its standard output and error.
fn run_line(dir: &Path, line: &str) -> Result<String, String> {
    let (cmd, redirect) = match line.split_once(" > ") {
        Some((c, f)) => (c, Some(f.trim())),
        None => (line, None),
    };
    let words = cmd.split_whitespace();
    let mut words = words.map(|w| if w == "fathom" { fathom() } else { w });
    let Some(program) = words.next() else {
        return Err("empty command".into());
    };
    let mut c = Command::new(program);
    c.args(words)
        .current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .stdin(Stdio::null())
        .stderr(Stdio::piped());
    let out_file = redirect.map(|f| dir.join(f));
    match &out_file {
        Some(f) => c.stdout(std::fs::File::create(f).map_err(|e| e.to_string())?),
        None => c.stdout(Stdio::piped()),
    };
    let mut child = c.spawn().map_err(|e| format!("{line}: {e}"))?;
    let start = Instant::now();
    loop {
        if child.try_wait().map_err(|e| e.to_string())?.is_some() {
            break;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            return Err(format!("{line}: still running after {TIMEOUT:?}"));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().map_err(|e| e.to_string())?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    if !out.status.success() {
        return Err(format!("{line}: {}\n{text}", out.status));
    }
    Ok(text)
}

/// Fraction of pixels that differ from the most common colour by more than 8 levels.
fn structure(img: &image::DynamicImage) -> f64 {
    let rgb = img.to_rgb8();
    let mut counts = std::collections::HashMap::new();
    for p in rgb.pixels() {
        *counts.entry(p.0.map(|c| c / 16)).or_insert(0u64) += 1;
    }
    let (mode, _) = counts.iter().max_by_key(|(_, n)| **n).expect("pixels");
    let bg = mode.map(|c| c * 16 + 8);
    let differ = rgb
        .pixels()
        .filter(|p| (0..3).any(|i| (p.0[i] as i32 - bg[i] as i32).abs() > 16))
        .count();
    differ as f64 / (rgb.width() * rgb.height()) as f64
}

/// Least fraction of pixels unlike the background for a picture to count as one.
const MIN_STRUCTURE: f64 = 0.02;

fn check_image(path: &Path, w: u32, h: u32) -> Result<(), String> {
    let img = image::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if w != 0 && (img.width(), img.height()) != (w, h) {
        return Err(format!(
            "{}: {}x{}, expected {w}x{h}",
            path.display(),
            img.width(),
            img.height()
        ));
    }
    let s = structure(&img);
    if s < MIN_STRUCTURE {
        return Err(format!(
            "{}: only {:.2}% of the pixels differ from the background: a blank picture",
            path.display(),
            100.0 * s
        ));
    }
    Ok(())
}

fn check_mesh(path: &Path) -> Result<(), String> {
    let b = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let ok = match ext {
        "stl" => {
            b.len() >= 84 && {
                let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
                n > 0 && b.len() == 84 + 50 * n
            }
        }
        "ply" => {
            b.starts_with(b"ply\n")
                && !String::from_utf8_lossy(&b[..b.len().min(400)]).contains("element face 0\n")
        }
        "obj" => String::from_utf8_lossy(&b)
            .lines()
            .any(|l| l.starts_with("f ")),
        "glb" => b.starts_with(b"glTF") && b.len() > 200,
        _ => false,
    };
    if ok {
        Ok(())
    } else {
        Err(format!(
            "{}: not a {ext} mesh with triangles",
            path.display()
        ))
    }
}

fn files_with(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == ext))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn check_expect(dir: &Path, e: Expect, said: &str) -> Result<(), String> {
    match e {
        Image(p, w, h) => check_image(&dir.join(p), w, h),
        Images(d, ext, n) => {
            let f = files_with(&dir.join(d), ext);
            if f.len() < n {
                return Err(format!("{d}: {} .{ext} files, expected {n}", f.len()));
            }
            check_image(&f[0], 0, 0)
        }
        Mesh(p) => check_mesh(&dir.join(p)),
        Meshes(d, ext, n) => {
            let f = files_with(&dir.join(d), ext);
            if f.len() < n {
                return Err(format!("{d}: {} .{ext} files, expected {n}", f.len()));
            }
            f.iter().try_for_each(|p| check_mesh(p))
        }
        Json(p) => {
            let text = if p == "-" {
                said.to_string()
            } else {
                std::fs::read_to_string(dir.join(p)).map_err(|e| format!("{p}: {e}"))?
            };
            // Standard output may follow progress lines on standard error: take the JSON.
            let start = text.find(['{', '[']).ok_or(format!("{p}: no JSON"))?;
            let mut de = serde_json::Deserializer::from_str(&text[start..]).into_iter();
            match de.next() {
                Some(Ok(serde_json::Value::Object(_))) | Some(Ok(serde_json::Value::Array(_))) => {
                    Ok(())
                }
                other => Err(format!("{p}: not JSON: {other:?}")),
            }
        }
        Scene(p) => run_line(dir, &format!("fathom scene {p} --check")).map(drop),
        Vol(p) => {
            let b = std::fs::read(dir.join(p)).map_err(|e| format!("{p}: {e}"))?;
            if b.starts_with(b"VOL\x03") && b.len() > 48 && b[48..].iter().any(|&x| x != 0) {
                Ok(())
            } else {
                Err(format!("{p}: not a .vol grid with density"))
            }
        }
        File(p) => match std::fs::metadata(dir.join(p)) {
            Ok(m) if m.len() > 0 => Ok(()),
            _ => Err(format!("{p}: missing or empty")),
        },
        Says(s) => {
            if said.contains(s) {
                Ok(())
            } else {
                Err(format!("output does not say `{s}`:\n{said}"))
            }
        }
    }
}

#[test]
fn examples_run_and_deliver_what_they_promise() {
    let dir = scratch();
    for (line, made) in SETUP {
        run_line(&dir, line).unwrap_or_else(|e| panic!("setup: {e}"));
        assert!(dir.join(made).exists(), "setup `{line}` made no {made}");
    }
    let mut failures = Vec::new();
    for case in CASES {
        let Run::Check {
            pre,
            rewrite,
            extra,
            expect,
        } = case.run
        else {
            continue;
        };
        let mut line = case.cmd.to_string();
        for (from, to) in rewrite {
            assert!(
                line.contains(from),
                "`{}`: rewrite `{from}` matches nothing",
                case.cmd
            );
            line = line.replace(from, to);
        }
        let (cmd, redirect) = match line.split_once(" > ") {
            Some((c, f)) => (c.to_string(), format!(" > {f}")),
            None => (line.clone(), String::new()),
        };
        let line = format!("{cmd} {}{redirect}", extra.join(" "));
        let t = Instant::now();
        let result = pre
            .iter()
            .try_for_each(|p| run_line(&dir, p).map(drop))
            .and_then(|()| run_line(&dir, line.trim()))
            .and_then(|said| {
                expect
                    .iter()
                    .try_for_each(|&e| check_expect(&dir, e, &said))
            });
        eprintln!(
            "{:>6.1} s  {}  {}",
            t.elapsed().as_secs_f64(),
            if result.is_ok() { "ok  " } else { "FAIL" },
            line.trim()
        );
        if let Err(e) = result {
            failures.push(format!("`{}` (run as `{}`): {e}", case.cmd, line.trim()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    let _ = std::fs::remove_dir_all(&dir);
}
