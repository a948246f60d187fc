//! The scene and its files: the scene tree with its camera, lights and render settings
//! ([`scene`], [`camera`]), the `.ron`/`.fract` files it is read from and written to
//! ([`scene_file`]), the built-in presets ([`presets`]) and scenes built in code ([`scenes`]).

pub mod camera;
pub mod presets;
pub mod scene;
pub mod scene_file;
pub mod scenes;
pub mod validate;
