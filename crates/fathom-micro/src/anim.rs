//! Textures that move: two keyframe scenes with the same structure (same shapes, operators and
//! tree), whose parameters and materials are blended by time. Only the parameter buffer
//! changes from frame to frame, so the GPU never rebuilds a shader or pipeline; whole-number
//! parameters (iteration counts) are rounded.

use fathom_core::registry::{Family, ParamKind};
use fathom_core::scene::{Call, Material, Node, Scene};

/// Why two keyframes cannot be blended.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("the keyframes differ in structure at {path}: {what}")]
pub struct KeyframeError {
    /// Where in the tree they differ (a node path).
    pub path: String,
    /// How they differ.
    pub what: String,
}

/// A texture animation: `from` at phase 0, `to` at phase 1, eased back and forth with period
/// `period` (seconds).
#[derive(Clone, Debug)]
pub struct Animation {
    /// The keyframe at phase 0.
    pub from: Scene,
    /// The keyframe at phase 1.
    pub to: Scene,
    /// Seconds from `from` to `to` and back.
    pub period: f64,
}

impl Animation {
    /// Checks the keyframes match (blending at phase 0 must succeed).
    pub fn new(from: Scene, to: Scene, period: f64) -> Result<Animation, KeyframeError> {
        blend(&from, &to, 0.0)?;
        Ok(Animation { from, to, period })
    }

    /// The blend weight at `time`: 0 at t = 0, 1 at half a period, smooth.
    pub fn weight(&self, time: f64) -> f64 {
        0.5 - 0.5 * (std::f64::consts::TAU * time / self.period.max(1e-9)).cos()
    }

    /// The scene at `time`.
    pub fn at(&self, time: f64) -> Scene {
        blend(&self.from, &self.to, self.weight(time)).expect("checked in new")
    }
}

fn lerp_call<K: Family + PartialEq + std::fmt::Debug>(
    a: &Call<K>,
    b: &Call<K>,
    w: f64,
    path: &str,
) -> Result<Call<K>, KeyframeError> {
    if a.kind != b.kind || a.params.len() != b.params.len() {
        return Err(KeyframeError {
            path: path.into(),
            what: format!("{:?} against {:?}", a.kind, b.kind),
        });
    }
    let mut out = a.clone();
    let mut slot = 0;
    for spec in a.kind.def().params {
        for _ in 0..spec.kind.width() {
            let v = a.params[slot] + (b.params[slot] - a.params[slot]) * w;
            out.params[slot] = if spec.kind == ParamKind::Int {
                v.round()
            } else {
                v
            };
            slot += 1;
        }
    }
    Ok(out)
}

fn lerp_material(a: &Material, b: &Material, w: f64) -> Material {
    let l = |x: f64, y: f64| x + (y - x) * w;
    Material {
        albedo: [0, 1, 2].map(|i| l(a.albedo[i], b.albedo[i])),
        specular: l(a.specular, b.specular),
        shininess: l(a.shininess, b.shininess),
        trap_colour: l(a.trap_colour, b.trap_colour),
        metallic: l(a.metallic, b.metallic),
        emission: [0, 1, 2].map(|i| l(a.emission[i], b.emission[i])),
        emission_strength: l(a.emission_strength, b.emission_strength),
        transmission: l(a.transmission, b.transmission),
        ior: l(a.ior, b.ior),
    }
}

fn lerp_node(a: &Node, b: &Node, w: f64, path: &str) -> Result<Node, KeyframeError> {
    if a.ops.len() != b.ops.len() || a.children.len() != b.children.len() {
        return Err(KeyframeError {
            path: path.into(),
            what: "different numbers of operators or children".into(),
        });
    }
    Ok(Node {
        combine: lerp_call(&a.combine, &b.combine, w, &format!("{path}.combine"))?,
        shape: lerp_call(&a.shape, &b.shape, w, &format!("{path}.shape"))?,
        ops: a
            .ops
            .iter()
            .zip(&b.ops)
            .enumerate()
            .map(|(i, (x, y))| lerp_call(x, y, w, &format!("{path}.ops[{i}]")))
            .collect::<Result<_, _>>()?,
        material: lerp_material(&a.material, &b.material, w),
        children: a
            .children
            .iter()
            .zip(&b.children)
            .enumerate()
            .map(|(i, (x, y))| lerp_node(x, y, w, &format!("{path}.children[{i}]")))
            .collect::<Result<_, _>>()?,
    })
}

/// `a` blended towards `b` by `w` in [0, 1]; the camera, lights and settings are `a`'s.
pub fn blend(a: &Scene, b: &Scene, w: f64) -> Result<Scene, KeyframeError> {
    let mut out = a.clone();
    out.root = lerp_node(&a.root, &b.root, w, "root")?;
    match (&a.ifs, &b.ifs) {
        (None, None) => {}
        (Some(x), Some(y)) if x.ops.len() == y.ops.len() => {
            let mut ifs = x.clone();
            ifs.iterations = (x.iterations as f64 + (y.iterations as f64 - x.iterations as f64) * w)
                .round() as u32;
            for (i, (o, (p, q))) in ifs.ops.iter_mut().zip(x.ops.iter().zip(&y.ops)).enumerate() {
                *o = lerp_call(p, q, w, &format!("ifs.ops[{i}]"))?;
            }
            out.ifs = Some(ifs);
        }
        _ => {
            return Err(KeyframeError {
                path: "ifs".into(),
                what: "one keyframe has an IFS loop the other lacks (or a different one)".into(),
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::Tape;
    use fathom_core::primitives::Primitive;

    fn sphere(r: f64) -> Scene {
        let mut s = Scene::new(Node::new(Call::new(Primitive::Sphere).with("radius", &[r])));
        s.root.material.albedo = [r / 2.0, 0.0, 0.0];
        s
    }

    #[test]
    fn blending_moves_parameters_and_keeps_the_instruction_stream() {
        let anim = Animation::new(sphere(0.5), sphere(1.5), 2.0).unwrap();
        let t0 = Tape::compile(&anim.at(0.0)).unwrap();
        let mid = anim.at(0.5);
        let t_half = Tape::compile(&anim.at(1.0)).unwrap();
        assert_eq!(t0.instrs(), t_half.instrs());
        assert!((t0.eval_f64([2.0, 0.0, 0.0]).d - 1.5).abs() < 1e-12);
        assert!((t_half.eval_f64([2.0, 0.0, 0.0]).d - 0.5).abs() < 1e-12);
        let r = mid.root.shape.get("radius").unwrap()[0];
        assert!((r - 1.0).abs() < 1e-12, "quarter period is half way: {r}");
        let mut t = t0.clone();
        t.update_params(&mid).unwrap();
    }

    #[test]
    fn mismatched_keyframes_name_the_place() {
        let mut b = sphere(1.0);
        b.root.children.push(Node::new(Primitive::Box));
        let e = Animation::new(sphere(1.0), b, 1.0).unwrap_err();
        assert_eq!(e.path, "root");
        let mut c = sphere(1.0);
        c.root.shape = Call::new(Primitive::Box).into();
        let e = Animation::new(sphere(1.0), c, 1.0).unwrap_err();
        assert_eq!(e.path, "root.shape");
    }
}
