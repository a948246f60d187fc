//! What one `fathom micro` run asks for, and how it is put together: mesh (file, built-in or a
//! demo's), texture (scene file, preset, a demo's, or a chaos-game cloud; exact, animated or
//! baked), shell and tiling, camera and image. The command line only parses into a
//! [`Request`]; everything that can be checked is checked here, before rendering starts.

use crate::anim::Animation;
use crate::chaos::{self, Cloud, Ifs};
use crate::error::MicroError;
use crate::grid::Grid;
use crate::mesh::{self, MeshReport, UvProjection};
use crate::render::{MicroScene, RenderOptions, fit_camera};
use crate::shade::Lighting;
use crate::shell::Shell;
use crate::texture::{Cell, Field, Texture, Tiling};
use fathom_core::scene::{Material, Scene};
use fathom_core::{presets, scene_file};
use glam::DVec3;

/// Where the texture comes from.
#[derive(Clone, Debug, Default)]
pub enum TextureSpec {
    /// The demo's (or, without a demo, the default preset `menger`).
    #[default]
    Default,
    /// A scene file.
    File(std::path::PathBuf),
    /// A built-in preset by name.
    Preset(String),
    /// A chaos-game system by name ([`chaos::SYSTEMS`]).
    Cloud(String),
}

/// Everything a run can ask for; `None` means "the default" (the demo's, or fitted).
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// The mesh: a file (OBJ, glTF) or a built-in mesh's name.
    pub mesh: Option<String>,
    /// A demo by name, which supplies every default below.
    pub demo: Option<String>,
    /// The texture.
    pub texture: TextureSpec,
    /// A second keyframe for an animated texture.
    pub texture_to: Option<std::path::PathBuf>,
    /// Seconds into the texture animation, [-1e9, 1e9].
    pub time: f64,
    /// Seconds from one keyframe to the other and back, [0.001, 1e9].
    pub period: f64,
    /// Shell height, mesh units (default: the demo's, or 3% of the mesh's diagonal).
    pub shell: Option<f64>,
    /// Texture tiles per UV unit (default: the demo's, or 1).
    pub tiles: Option<f64>,
    /// The box of texture-scene space one tile fills (default: [-1, 1]^3).
    pub cell: Option<Cell>,
    /// The UV projection for a mesh without UVs.
    pub uv: Option<UvProjection>,
    /// Bake the texture into an n^3 grid.
    pub bake: Option<u32>,
    /// Points of a chaos-game cloud.
    pub cloud_points: u64,
    /// Radius of the sphere around each cloud point, texture-scene units.
    pub cloud_radius: f64,
    /// Seed of the chaos game.
    pub cloud_seed: u64,
    /// Whether the base mesh is drawn under the shell.
    pub show_base: bool,
    /// Rotate texture normals onto the interpolated vertex normals.
    pub smooth_normals: bool,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The camera's eye (default: fitted to the object).
    pub eye: Option<DVec3>,
    /// The point looked at (default: fitted to the object).
    pub target: Option<DVec3>,
    /// The camera's up direction (default: fitted).
    pub up: Option<DVec3>,
    /// Vertical field of view, degrees (default: 40).
    pub fov: Option<f64>,
}

impl Request {
    /// Defaults for everything (no mesh, no demo).
    pub fn new() -> Request {
        Request {
            period: 4.0,
            cloud_points: 400_000,
            cloud_radius: 0.004,
            cloud_seed: 1,
            show_base: true,
            smooth_normals: true,
            width: 1280,
            height: 720,
            ..Default::default()
        }
    }
}

/// A prepared run: a shell scene, or a texture on its own (a cloud without a mesh).
pub enum Prepared {
    /// A texture pasted over a mesh's shell.
    Shell {
        /// The shell, its texture and lighting.
        scene: Box<MicroScene>,
        /// How to render it.
        options: RenderOptions,
        /// What cleaning the mesh found.
        mesh_report: MeshReport,
        /// The texture's keyframe scene at the requested time (the GPU path uploads its tape).
        texture_scene: Option<Box<Scene>>,
    },
    /// A texture on its own in its cell (a cloud without a mesh).
    Alone {
        /// The texture.
        texture: Box<Texture>,
        /// The box of texture-scene space drawn.
        cell: Cell,
        /// Lights and sky.
        lighting: Lighting,
        /// How to render it.
        options: RenderOptions,
    },
}

fn texture_error(origin: &str, e: impl ToString) -> MicroError {
    MicroError::Texture {
        origin: origin.into(),
        msg: e.to_string(),
    }
}

fn load_scene(
    spec: &TextureSpec,
    demo: Option<&crate::demo::Demo>,
) -> Result<(Scene, String), MicroError> {
    match spec {
        TextureSpec::File(p) => {
            let o = p.display().to_string();
            Ok((scene_file::load(p).map_err(|e| texture_error(&o, e))?, o))
        }
        TextureSpec::Preset(n) => Ok((
            presets::load(n).map_err(|e| texture_error(n, e))?,
            format!("<preset:{n}>"),
        )),
        TextureSpec::Default | TextureSpec::Cloud(_) => match demo {
            Some(d) => Ok((d.texture.clone(), d.texture_origin.clone())),
            None => Ok((
                presets::load("menger").map_err(|e| texture_error("menger", e))?,
                "<preset:menger>".into(),
            )),
        },
    }
}

impl Request {
    /// Loads, checks and builds everything.
    pub fn prepare(&self) -> Result<Prepared, MicroError> {
        crate::error::check_range("time", self.time, -1e9, 1e9, "[-1e9, 1e9] seconds")?;
        crate::error::check_range("period", self.period, 1e-3, 1e9, "[0.001, 1e9] seconds")?;
        let demo = self.demo.as_deref().map(crate::demo::load).transpose()?;
        let (mut scene, origin) = load_scene(&self.texture, demo.as_ref())?;
        if let Some(to) = &self.texture_to {
            let o = to.display().to_string();
            let b = scene_file::load(to).map_err(|e| texture_error(&o, e))?;
            let anim = Animation::new(scene, b, self.period).map_err(|e| texture_error(&o, e))?;
            scene = anim.at(self.time);
        }
        let lighting = Lighting::from_scene(&scene);
        let cell = self.cell.unwrap_or(Cell::UNIT);
        let texture = match &self.texture {
            TextureSpec::Cloud(name) => {
                let ifs = Ifs::named(name)?;
                let mut pts = ifs.points(self.cloud_points, self.cloud_seed)?;
                chaos::fit_to_cell(&mut pts, cell);
                let cloud = Cloud::new(&pts, self.cloud_radius, cell, 48)?;
                // --bake gives the seed's approach: the cloud's exact distances on a grid.
                let (field, how) = match self.bake {
                    Some(n) => (
                        Field::Grid(Grid::bake_with(cell, n, |_, q| (cloud.exact(q), 0))?),
                        format!(" baked at {n}^3"),
                    ),
                    None => (Field::Cloud(cloud), String::new()),
                };
                Texture {
                    field,
                    materials: vec![Material {
                        albedo: if name == "fern" {
                            [0.25, 0.6, 0.2]
                        } else {
                            [0.55, 0.45, 0.3]
                        },
                        specular: 0.2,
                        shininess: 24.0,
                        trap_colour: 0.0,
                        ..Material::default()
                    }],
                    origin: format!("<cloud:{name}>{how}"),
                }
            }
            _ => {
                let t = Texture::from_scene(&scene, &origin)?;
                match self.bake {
                    Some(n) => {
                        let tape = t.tape().expect("an exact texture");
                        Texture {
                            field: Field::Grid(Grid::bake(tape, cell, n)?),
                            materials: t.materials,
                            origin: format!("{origin} baked at {n}^3"),
                        }
                    }
                    None => t,
                }
            }
        };
        let mesh_spec = self
            .mesh
            .clone()
            .or_else(|| demo.as_ref().map(|d| d.name.to_string()));
        let fov = self.fov.unwrap_or(40.0);
        let camera_for = |bounds: (DVec3, DVec3), from: DVec3| {
            let mut c = fit_camera(bounds, from, fov, self.width as f64 / self.height as f64);
            if let Some(v) = self.eye {
                c.eye = v;
            }
            if let Some(v) = self.target {
                c.target = v;
            }
            if let Some(v) = self.up {
                c.up = v;
            }
            c
        };
        let Some(spec) = mesh_spec else {
            // A texture on its own.
            let options = RenderOptions {
                width: self.width,
                height: self.height,
                camera: camera_for((cell.min, cell.max), DVec3::new(0.8, 0.35, 1.4)),
                smooth_normals: self.smooth_normals,
                ..Default::default()
            };
            options.validate()?;
            return Ok(Prepared::Alone {
                texture: Box::new(texture),
                cell,
                lighting,
                options,
            });
        };
        let (mesh, mesh_report) = match (&demo, self.mesh.is_none()) {
            (Some(d), true) => (d.mesh.clone(), d.mesh_report.clone()),
            _ => mesh::load(&spec, self.uv)?,
        };
        let (lo, hi) = mesh.bounds();
        let height = self
            .shell
            .or(demo.as_ref().map(|d| d.shell_height))
            .unwrap_or(0.03 * (hi - lo).length());
        let tiling = Tiling {
            tiles: self
                .tiles
                .or(demo.as_ref().map(|d| d.tiling.tiles))
                .unwrap_or(1.0),
            cell,
        };
        let shell = Shell::build(&mesh, height, &tiling)?;
        let from = demo
            .as_ref()
            .map_or(DVec3::new(0.9, 0.6, 1.5), |d| d.view_from);
        let options = RenderOptions {
            width: self.width,
            height: self.height,
            camera: camera_for(shell.bounds, from),
            smooth_normals: self.smooth_normals,
            ..Default::default()
        };
        options.validate()?;
        let base = self.show_base.then(|| {
            demo.as_ref().map_or(
                Material {
                    albedo: [0.4, 0.4, 0.42],
                    specular: 0.1,
                    shininess: 16.0,
                    trap_colour: 0.0,
                    ..Material::default()
                },
                |d| d.base.clone(),
            )
        });
        let is_exact = texture.tape().is_some();
        Ok(Prepared::Shell {
            scene: Box::new(MicroScene::new(shell, texture, lighting, base)),
            options,
            mesh_report,
            texture_scene: is_exact.then(|| Box::new(scene)),
        })
    }
}

/// Parses `n` comma-separated finite numbers.
pub fn parse_numbers(s: &str, n: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}` should be {n} comma-separated numbers"))?;
    if v.len() != n || !v.iter().all(|x| x.is_finite()) {
        return Err(format!(
            "`{s}` should be {n} comma-separated finite numbers"
        ));
    }
    Ok(v)
}

/// Parses a cell `x0,y0,z0,x1,y1,z1`.
pub fn parse_cell(s: &str) -> Result<Cell, String> {
    let v = parse_numbers(s, 6)?;
    let c = Cell {
        min: DVec3::new(v[0], v[1], v[2]),
        max: DVec3::new(v[3], v[4], v[5]),
    };
    if !(c.max.cmpgt(c.min).all()) {
        return Err(format!("cell `{s}`: each max must exceed its min"));
    }
    Ok(c)
}
