//! The tape: a scene compiled into one flat program that the CPU interpreter (`eval`) and the
//! WGSL interpreter both run. `docs/tape.md` is the normative description of the encoding.
//!
//! A tape is an instruction stream (four `u32` words per instruction), a parameter buffer
//! (f64 on the CPU, converted to f32 for the GPU) and a material table. Editing a parameter
//! rewrites only the parameter buffer and material table ([`Tape::update_params`]); editing
//! the structure compiles a new tape ([`Tape::compile`]).

use crate::limits;
use crate::registry::Family;
use crate::scene::{Call, DomainOp, Material, Node, Scene, Shape};
use crate::transforms::Transform;
use thiserror::Error;

/// Opcode families: the high bits of an opcode (`op >> 8`). The low byte is the index of the
/// entry within its registry family.
pub mod family {
    /// Control flow: End, PushPoint, PopPoint, LoopBegin, LoopEnd.
    pub const CONTROL: u32 = 0;
    /// `Primitive` distance; pushes a value.
    pub const PRIMITIVE: u32 = 1;
    /// `Fractal` distance estimate; pushes a value.
    pub const FRACTAL: u32 = 2;
    /// `Transform` applied to the current point.
    pub const TRANSFORM: u32 = 3;
    /// `Modifier` applied to the top value.
    pub const MODIFIER: u32 = 4;
    /// `Combine`: pops the child value `b`, then the parent value `a`, pushes the result.
    pub const COMBINE: u32 = 5;
}

/// Control opcodes (family 0).
pub mod control {
    /// Stop; the single value on the value stack is the result.
    pub const END: u32 = 0;
    /// Save the current point (with its distance scale and trap) on the point stack.
    pub const PUSH_POINT: u32 = 1;
    /// Restore the current point from the point stack.
    pub const POP_POINT: u32 = 2;
    /// Start a loop running `params[param]` times; `arg` is the index just after its LoopEnd.
    pub const LOOP_BEGIN: u32 = 3;
    /// Update the orbit trap, count one iteration, and jump back to `arg` (the first body
    /// instruction) while iterations remain.
    pub const LOOP_END: u32 = 4;
}

/// One tape instruction: four little-endian `u32` words, identical on CPU and GPU.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Instr {
    /// `family << 8 | index`.
    pub op: u32,
    /// Offset of this instruction's parameters in the parameter buffer.
    pub param: u32,
    /// Per-opcode argument: material id for shapes, jump target for loops, otherwise 0.
    pub arg: u32,
    /// Reserved, 0.
    pub reserved: u32,
}

impl Instr {
    fn new(family: u32, index: usize, param: usize, arg: u32) -> Self {
        Instr {
            op: family << 8 | index as u32,
            param: param as u32,
            arg,
            reserved: 0,
        }
    }
    /// The opcode family.
    #[inline(always)]
    pub fn family(&self) -> u32 {
        self.op >> 8
    }
    /// The index within the family.
    #[inline(always)]
    pub fn index(&self) -> usize {
        (self.op & 0xff) as usize
    }
    /// A readable name for listings and error messages.
    pub fn name(&self) -> String {
        let i = self.index();
        let name = |defs: &[crate::registry::Def]| defs.get(i).map_or("?", |d| d.name).to_string();
        match self.family() {
            family::CONTROL => ["End", "PushPoint", "PopPoint", "LoopBegin", "LoopEnd"]
                .get(i)
                .unwrap_or(&"?")
                .to_string(),
            family::PRIMITIVE => name(crate::primitives::PRIMITIVES),
            family::FRACTAL => name(crate::fractals::FRACTALS),
            family::TRANSFORM => name(crate::transforms::TRANSFORMS),
            family::MODIFIER => name(crate::modifiers::MODIFIERS),
            family::COMBINE => name(crate::combine::COMBINES),
            _ => "?".into(),
        }
    }
}

/// Why a scene did not compile.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum CompileError {
    /// The scene breaks a rule of validation.
    #[error("invalid scene: {0}")]
    Invalid(#[from] crate::validate::SceneError),
    /// The tape would exceed `limits::MAX_TAPE_LEN` instructions (the count it would have).
    #[error("the tape would have {0} instructions; the limit is {max}", max = limits::MAX_TAPE_LEN)]
    TooLong(usize),
    /// The parameter buffer would exceed `limits::MAX_PARAMS` slots (the count it would have).
    #[error("the parameter buffer would have {0} slots; the limit is {max}", max = limits::MAX_PARAMS)]
    TooManyParams(usize),
    /// A parameter update was given a scene whose tree no longer matches the tape.
    #[error("the scene's structure changed; compile a new tape")]
    StructureChanged,
}

/// A compiled scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Tape {
    instrs: Vec<Instr>,
    params: Vec<f64>,
    materials: Vec<Material>,
    max_points: usize,
    max_values: usize,
    structure: u64,
}

/// Walks a scene in tape order; emits instructions when `instrs` is set, always bakes params.
struct Emitter<'a> {
    instrs: Option<&'a mut Vec<Instr>>,
    params: Vec<f64>,
    materials: Vec<Material>,
    structure: u64,
    len: usize,
    points: usize,
    max_points: usize,
    values: usize,
    max_values: usize,
}

impl Emitter<'_> {
    fn emit(&mut self, family: u32, index: usize, param: usize, arg: u32) -> usize {
        let at = self.len;
        // FNV-1a over the opcode stream: the structure signature.
        self.structure =
            (self.structure ^ (family << 8 | index as u32) as u64).wrapping_mul(0x100_0000_01b3);
        if let Some(v) = self.instrs.as_deref_mut() {
            v.push(Instr::new(family, index, param, arg));
        }
        self.len += 1;
        at
    }

    fn patch_arg(&mut self, at: usize, arg: u32) {
        if let Some(v) = self.instrs.as_deref_mut() {
            v[at].arg = arg;
        }
    }

    fn bake<K: Family>(&mut self, call: &Call<K>) -> usize {
        let off = self.params.len();
        call.kind.def().bake_into(&call.params, &mut self.params);
        off
    }

    fn push_point(&mut self) {
        self.emit(family::CONTROL, control::PUSH_POINT as usize, 0, 0);
        self.points += 1;
        self.max_points = self.max_points.max(self.points);
    }

    fn pop_point(&mut self) {
        self.emit(family::CONTROL, control::POP_POINT as usize, 0, 0);
        self.points -= 1;
    }

    fn push_value(&mut self) {
        self.values += 1;
        self.max_values = self.max_values.max(self.values);
    }

    fn transform(&mut self, t: &Call<Transform>) {
        let off = self.bake(t);
        self.emit(family::TRANSFORM, t.kind.index(), off, 0);
    }

    fn node(&mut self, n: &Node) {
        let id = self.materials.len() as u32;
        self.materials.push(n.material.clone());
        let has_point_ops = n
            .ops
            .iter()
            .any(|o| matches!(o.kind, DomainOp::Transform(_)));
        if has_point_ops {
            self.push_point();
        }
        for op in &n.ops {
            if let DomainOp::Transform(t) = op.kind {
                self.transform(&Call {
                    kind: t,
                    params: op.params.clone(),
                });
            }
        }
        let off = self.bake(&n.shape);
        match n.shape.kind {
            Shape::Primitive(p) => self.emit(family::PRIMITIVE, p.index(), off, id),
            Shape::Fractal(f) => self.emit(family::FRACTAL, f.index(), off, id),
        };
        self.push_value();
        for c in &n.children {
            self.node(c);
            let off = self.bake(&c.combine);
            self.emit(family::COMBINE, c.combine.kind.index(), off, 0);
            self.values -= 1;
        }
        for op in &n.ops {
            if let DomainOp::Modifier(m) = op.kind {
                let off = self.bake(&Call {
                    kind: m,
                    params: op.params.clone(),
                });
                self.emit(family::MODIFIER, m.index(), off, 0);
            }
        }
        if has_point_ops {
            self.pop_point();
        }
    }

    fn scene(&mut self, s: &Scene) {
        if let Some(ifs) = &s.ifs {
            let count = self.params.len();
            self.params.push(ifs.iterations as f64);
            let begin = self.emit(family::CONTROL, control::LOOP_BEGIN as usize, count, 0);
            for t in &ifs.ops {
                self.transform(t);
            }
            self.emit(
                family::CONTROL,
                control::LOOP_END as usize,
                0,
                begin as u32 + 1,
            );
            let after = self.len as u32;
            self.patch_arg(begin, after);
        }
        self.node(&s.root);
        self.emit(family::CONTROL, control::END as usize, 0, 0);
    }
}

/// Counts the instructions and parameter slots a scene will need, without allocating them.
fn measure(s: &Scene) -> (usize, usize) {
    fn node(n: &Node, acc: &mut (usize, usize)) {
        let point_ops = n
            .ops
            .iter()
            .filter(|o| matches!(o.kind, DomainOp::Transform(_)))
            .count();
        acc.0 += n.ops.len() + 1 + n.children.len() + if point_ops > 0 { 2 } else { 0 };
        acc.1 += n.ops.iter().map(|o| o.kind.def().baked_len).sum::<usize>()
            + n.shape.kind.def().baked_len
            + n.children
                .iter()
                .map(|c| c.combine.kind.def().baked_len)
                .sum::<usize>();
        for c in &n.children {
            node(c, acc);
        }
    }
    let mut acc = (1, 0);
    if let Some(ifs) = &s.ifs {
        acc.0 += 2 + ifs.ops.len();
        acc.1 += 1 + ifs
            .ops
            .iter()
            .map(|o| o.kind.def().baked_len)
            .sum::<usize>();
    }
    node(&s.root, &mut acc);
    acc
}

impl Tape {
    /// Validates and compiles a scene. Limits are checked before the tape is allocated.
    pub fn compile(scene: &Scene) -> Result<Tape, CompileError> {
        scene.validate().map_err(CompileError::Invalid)?;
        let (len, nparams) = measure(scene);
        if len > limits::MAX_TAPE_LEN {
            return Err(CompileError::TooLong(len));
        }
        if nparams > limits::MAX_PARAMS {
            return Err(CompileError::TooManyParams(nparams));
        }
        let mut instrs = Vec::with_capacity(len);
        let mut e = Emitter {
            instrs: Some(&mut instrs),
            params: Vec::with_capacity(nparams),
            materials: Vec::with_capacity(scene.root.count()),
            structure: 0xcbf2_9ce4_8422_2325,
            len: 0,
            points: 1,
            max_points: 1,
            values: 0,
            max_values: 0,
        };
        e.scene(scene);
        let (params, materials, structure, max_points, max_values) = (
            e.params,
            e.materials,
            e.structure,
            e.max_points,
            e.max_values,
        );
        debug_assert_eq!(instrs.len(), len);
        debug_assert_eq!(params.len(), nparams);
        Ok(Tape {
            instrs,
            params,
            materials,
            max_points,
            max_values,
            structure,
        })
    }

    /// Re-bakes the parameter buffer and material table from an edited scene whose structure
    /// (shapes, operators, tree shape) is unchanged. The instruction stream is not touched.
    pub fn update_params(&mut self, scene: &Scene) -> Result<(), CompileError> {
        scene.validate().map_err(CompileError::Invalid)?;
        let mut e = Emitter {
            instrs: None,
            params: Vec::with_capacity(self.params.len()),
            materials: Vec::with_capacity(self.materials.len()),
            structure: 0xcbf2_9ce4_8422_2325,
            len: 0,
            points: 1,
            max_points: 1,
            values: 0,
            max_values: 0,
        };
        e.scene(scene);
        if e.structure != self.structure
            || e.len != self.instrs.len()
            || e.params.len() != self.params.len()
        {
            return Err(CompileError::StructureChanged);
        }
        self.params = e.params;
        self.materials = e.materials;
        Ok(())
    }

    /// The instruction stream.
    pub fn instrs(&self) -> &[Instr] {
        &self.instrs
    }
    /// The parameter buffer (f64; the GPU receives [`Tape::params_f32`]).
    pub fn params(&self) -> &[f64] {
        &self.params
    }
    /// The parameter buffer converted to f32 for the GPU.
    pub fn params_f32(&self) -> Vec<f32> {
        self.params.iter().map(|&x| x as f32).collect()
    }
    /// Materials indexed by the material ids in shape instructions (one per node, pre-order).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }
    /// Deepest point stack the tape needs (including the current point).
    pub fn max_points(&self) -> usize {
        self.max_points
    }
    /// Deepest value stack the tape needs.
    pub fn max_values(&self) -> usize {
        self.max_values
    }
    /// The instruction words, flat, as uploaded to the GPU.
    pub fn words(&self) -> Vec<u32> {
        self.instrs
            .iter()
            .flat_map(|i| [i.op, i.param, i.arg, i.reserved])
            .collect()
    }
    /// A readable listing, one instruction per line.
    pub fn listing(&self) -> String {
        let mut s = String::new();
        for (i, ins) in self.instrs.iter().enumerate() {
            s += &format!(
                "{i:4}  {:<16} param={:<5} arg={}\n",
                ins.name(),
                ins.param,
                ins.arg
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::combine::Combine;
    use crate::primitives::Primitive;
    use crate::reference::eval_tree;
    use crate::scene::Ifs;
    use crate::validate::SceneError;

    fn two_spheres() -> Scene {
        Scene::new(
            Node::new(Primitive::Sphere).child(
                Node::new(Primitive::Sphere)
                    .combine(Combine::SmoothUnion)
                    .op(Call::new(Transform::Translate).with("offset", &[1.5, 0.0, 0.0])),
            ),
        )
    }

    #[test]
    fn parameter_edits_only_rewrite_parameters() {
        let mut s = two_spheres();
        let mut tape = Tape::compile(&s).unwrap();
        let instrs = tape.instrs().to_vec();
        s.root.children[0].ops[0]
            .set("offset", &[3.0, 0.0, 0.0])
            .unwrap();
        s.root.material.albedo = [1.0, 0.0, 0.0];
        tape.update_params(&s).unwrap();
        assert_eq!(tape.instrs(), &instrs[..]);
        assert_eq!(tape.materials()[0].albedo, [1.0, 0.0, 0.0]);
        assert_eq!(tape, Tape::compile(&s).unwrap());
        // At x = 3 the moved sphere's centre: distance -1.
        assert!((tape.eval_f64([3.0, 0.0, 0.0]).d + 1.0).abs() < 1e-12);
    }

    #[test]
    fn structure_edits_are_refused_by_update_params() {
        let s = two_spheres();
        let mut tape = Tape::compile(&s).unwrap();
        let mut t = s.clone();
        t.root.children[0].shape = Call::new(Primitive::Box).into();
        assert_eq!(tape.update_params(&t), Err(CompileError::StructureChanged));
        let mut t = s.clone();
        t.root.children.push(Node::new(Primitive::Sphere));
        assert_eq!(tape.update_params(&t), Err(CompileError::StructureChanged));
        assert_eq!(
            tape,
            Tape::compile(&s).unwrap(),
            "a refused update leaves the tape intact"
        );
    }

    #[test]
    fn limits_are_checked_before_allocation() {
        let mut deep = Node::new(Primitive::Sphere);
        for _ in 0..limits::MAX_TREE_DEPTH {
            deep = Node::new(Primitive::Sphere).child(deep);
        }
        let e = Tape::compile(&Scene::new(deep)).unwrap_err();
        assert!(
            matches!(
                &e,
                CompileError::Invalid(SceneError::TooDeep { depth }) if *depth == limits::MAX_TREE_DEPTH + 1
            ) && e.to_string().contains("levels deep"),
            "{e}"
        );

        let wide = Node {
            children: vec![Node::new(Primitive::Sphere); limits::MAX_NODES],
            ..Node::new(Primitive::Sphere)
        };
        let e = Tape::compile(&Scene::new(wide)).unwrap_err();
        assert!(
            matches!(&e, CompileError::Invalid(SceneError::TooManyNodes { .. }))
                && e.to_string().contains("nodes"),
            "{e}"
        );

        let mut s = two_spheres();
        s.root.shape.params[0] = f64::NAN;
        assert!(Tape::compile(&s).is_err());
        s.root.shape.params[0] = -1.0;
        assert!(Tape::compile(&s).is_err());
    }

    #[test]
    fn ifs_loop_runs_its_iteration_count_and_zero_skips_it() {
        let mut s = Scene::new(Node::new(Primitive::Sphere));
        s.ifs = Some(Ifs {
            iterations: 0,
            ops: vec![Call::new(Transform::ScaleAbout)],
        });
        let t0 = Tape::compile(&s).unwrap();
        assert_eq!(t0.eval_f64([2.0, 0.0, 0.0]).d, 1.0);
        for n in [1, 2, 5] {
            s.ifs.as_mut().unwrap().iterations = n;
            let mut t = t0.clone();
            t.update_params(&s).unwrap();
            for p in [[2.0, 0.3, -0.1], [0.2, 0.1, 0.0]] {
                assert_eq!(t.eval_f64(p).d, eval_tree(&s, p).d, "n = {n}");
            }
        }
    }

    #[test]
    fn stack_depths_are_reported() {
        let t = Tape::compile(&two_spheres()).unwrap();
        assert_eq!(t.max_values(), 2);
        assert_eq!(t.max_points(), 2);
        assert_eq!(t.words().len(), 4 * t.instrs().len());
        assert!(t.listing().contains("SmoothUnion"));
    }
}
