//! A texture rendered on its own, in its own texture-scene space (no mesh, no shell): how a
//! chaos-game cloud is shown alone, and the reference the shell renderer is checked against.
//! Rays are clipped to the texture's cell and sphere traced with the texture's distance bound.

use crate::error::MicroError;
use crate::render::{MicroStats, RenderOptions};
use crate::shade::Lighting;
use crate::texture::{Cell, Texture};
use fathom_core::Evaluator;
use fathom_core::frame::{Frame, NO_ID};
use glam::DVec3;
use rayon::prelude::*;
use std::time::Instant;

/// Where the ray `o + t d` is inside `cell`: (t_in, t_out), t_in clamped to 0.
pub fn clip_box(cell: &Cell, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let inv = d.recip();
    let a = (cell.min - o) * inv;
    let b = (cell.max - o) * inv;
    let t0 = a.min(b).max_element().max(0.0);
    let t1 = a.max(b).min_element();
    (t0 < t1).then_some((t0, t1))
}

/// Renders `tex` inside `cell` with the camera of `o`.
pub fn render(
    tex: &Texture,
    cell: &Cell,
    lighting: &Lighting,
    o: &RenderOptions,
) -> Result<(Frame, MicroStats), MicroError> {
    let start = Instant::now();
    o.validate()?;
    let cam = o.camera.frame();
    let p = o.march_params();
    let pa = o.pixel_angle();
    let (w, h) = (o.width, o.height);
    type Px = ([f32; 3], f32, [f32; 3], u32, u32, u64);
    let rows: Vec<Vec<Px>> = (0..h)
        .into_par_iter()
        .map_init(Evaluator::<f64>::new, |ev, y| {
            (0..w)
                .map(|x| {
                    let d = cam.ray_dir(x as f64 + 0.5, y as f64 + 0.5, w, h);
                    let sky = lighting.sky(d).as_vec3().to_array();
                    let Some((t0, t1)) = clip_box(cell, cam.eye, d) else {
                        return (sky, f32::INFINITY, [0.0; 3], NO_ID, 0, 0);
                    };
                    let mut t = t0;
                    let mut steps = 0u32;
                    while t < t1 && steps < p.max_steps {
                        let q = cam.eye + d * t;
                        let dist = tex.distance(ev, q);
                        steps += 1;
                        if dist < p.eps_slope * t + p.eps_min {
                            let n = tex.normal(ev, q, 0.5 * pa * t);
                            let id = tex.material_id(ev, q);
                            let c = lighting.shade(&tex.materials[id as usize], n, d);
                            return (
                                c.as_vec3().to_array(),
                                t as f32,
                                n.as_vec3().to_array(),
                                id,
                                steps,
                                5,
                            );
                        }
                        t += dist;
                    }
                    (sky, f32::INFINITY, [0.0; 3], NO_ID, steps, 0)
                })
                .collect()
        })
        .collect();
    let mut f = Frame::new(w, h);
    let mut s = MicroStats {
        width: w,
        height: h,
        ..Default::default()
    };
    for (i, px) in rows.into_iter().flatten().enumerate() {
        (f.colour[i], f.depth[i], f.normal[i], f.id[i], f.steps[i]) =
            (px.0, px.1, px.2, px.3, px.4);
        s.de_march += px.4 as u64;
        s.de_shade += px.5;
        if px.1.is_finite() {
            s.hits += 1;
            s.texture_hits += 1;
        }
    }
    s.ms_total = start.elapsed().as_secs_f64() * 1e3;
    Ok((f, s))
}
