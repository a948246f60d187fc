//! fathom-image: what happens to a rendered [`Frame`] after the renderer, whichever renderer
//! made it (CPU tracer, GPU, octree, volume, mesh preview).
//!
//! - [`post`]: effects on a frame (fog, SSAO, supersampling, tonemap, sRGB);
//! - [`output`]: files (8/16-bit PNG, hit mask, depth EXR, layered EXR, step heat map, JSON),
//!   numbered names for sequences, and a camera path as glTF for other tools;
//! - [`stereo`]: the side-by-side and top/bottom layouts of stereo views;
//! - [`compare`]: how alike two pictures are (SSIM, silhouette IoU, colour error).
//!
//! Every file is written atomically through [`fathom_core::atomic_file`].
//!
//! A first use: a small frame, one pixel lit, written as a PNG.
//!
//! ```
//! use fathom_core::frame::Frame;
//! use fathom_image::output::{open_output, save_colour};
//!
//! let mut frame = Frame::new(4, 3);
//! frame.colour[0] = [1.0, 0.5, 0.25];
//! frame.depth[0] = 2.0;
//! let path = std::env::temp_dir().join(format!("fathom-image-doc-{}.png", std::process::id()));
//! let file = open_output(&path)?;
//! save_colour(&frame, file, &path)?;
//! assert!(path.exists());
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), fathom_image::output::OutputError>(())
//! ```
//!
//! [`Frame`]: fathom_core::frame::Frame

#![warn(missing_docs)]

pub mod compare;
pub mod output;
pub mod post;
pub mod stereo;
