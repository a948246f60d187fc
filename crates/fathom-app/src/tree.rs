//! The scene-tree editor: the tree (select, add, duplicate, remove, reorder, reparent by drag)
//! and the inspector of the selected node (its primitive or fractal and parameters, the
//! combine operator and its smoothness, the ordered domain operators, the material), plus the
//! root's IFS loop. Every picker and slider comes from the registry ([`crate::params`]).
//!
//! The tree is drawn from the scene and returns [`TreeAction`]s, applied after the pass by
//! [`apply`], which refuses moves that would make a node its own ancestor.

use crate::params::{call_params, entry_picker};
use fathom_core::combine::Combine;
use fathom_core::limits;
use fathom_core::primitives::Primitive;
use fathom_core::registry::Family;
use fathom_core::scene::{Call, Ifs, Material, Node, Scene, Shape};
use fathom_core::transforms::Transform;

/// A node's place: child indices from the root (empty: the root).
pub type NodePath = Vec<usize>;

/// A structural edit of the tree.
#[derive(Clone, Debug, PartialEq)]
pub enum TreeAction {
    /// Selects the node.
    Select(NodePath),
    /// Adds a sphere as the node's last child, and selects it.
    AddChild(NodePath),
    /// Inserts a copy of the node (and its subtree) after it, and selects the copy.
    Duplicate(NodePath),
    /// Removes the node and its subtree (not the root).
    Remove(NodePath),
    /// Swaps the node with its previous sibling.
    MoveUp(NodePath),
    /// Swaps the node with its next sibling.
    MoveDown(NodePath),
    /// Makes `node` the last child of `parent`.
    Reparent {
        /// The node moved.
        node: NodePath,
        /// Its new parent.
        parent: NodePath,
    },
}

impl TreeAction {
    /// A label for the undo history.
    pub fn label(&self) -> &'static str {
        match self {
            TreeAction::Select(_) => "select",
            TreeAction::AddChild(_) => "add node",
            TreeAction::Duplicate(_) => "duplicate node",
            TreeAction::Remove(_) => "remove node",
            TreeAction::MoveUp(_) | TreeAction::MoveDown(_) => "reorder nodes",
            TreeAction::Reparent { .. } => "move node",
        }
    }
}

/// The node at `path`.
pub fn node_at<'a>(root: &'a Node, path: &[usize]) -> Option<&'a Node> {
    path.iter().try_fold(root, |n, &i| n.children.get(i))
}

/// The node at `path`, mutably.
pub fn node_at_mut<'a>(root: &'a mut Node, path: &[usize]) -> Option<&'a mut Node> {
    path.iter().try_fold(root, |n, &i| n.children.get_mut(i))
}

/// A short label for a node: its shape, and its combine unless it is the root.
pub fn node_label(n: &Node, is_root: bool) -> String {
    if is_root {
        n.shape.kind.def().name.to_string()
    } else {
        format!(
            "{} ({})",
            n.shape.kind.def().name,
            n.combine.kind.def().name
        )
    }
}

/// Applies a structural edit; `selected` follows the edited node. Errors say why an edit was
/// refused (the scene is then unchanged).
pub fn apply(scene: &mut Scene, a: &TreeAction, selected: &mut NodePath) -> Result<(), String> {
    let root = &mut scene.root;
    match a {
        TreeAction::Select(p) => {
            node_at(root, p).ok_or("no such node")?;
            *selected = p.clone();
        }
        TreeAction::AddChild(p) => {
            if root.count() >= limits::MAX_NODES {
                return Err(format!(
                    "the scene already has the most nodes ({})",
                    limits::MAX_NODES
                ));
            }
            let n = node_at_mut(root, p).ok_or("no such node")?;
            n.children
                .push(Node::new(Primitive::Sphere).combine(Combine::Union));
            *selected = p.iter().copied().chain([n.children.len() - 1]).collect();
        }
        TreeAction::Duplicate(p) => {
            let (last, parent) = p.split_last().ok_or("the root cannot be duplicated")?;
            let copy = node_at(root, p).ok_or("no such node")?.clone();
            if root.count() + copy.count() > limits::MAX_NODES {
                return Err(format!("the copy would exceed {} nodes", limits::MAX_NODES));
            }
            let parent_node = node_at_mut(root, parent).ok_or("no such node")?;
            parent_node.children.insert(last + 1, copy);
            *selected = parent.iter().copied().chain([last + 1]).collect();
        }
        TreeAction::Remove(p) => {
            let (last, parent) = p.split_last().ok_or("the root cannot be removed")?;
            let parent_node = node_at_mut(root, parent).ok_or("no such node")?;
            if *last >= parent_node.children.len() {
                return Err("no such node".into());
            }
            parent_node.children.remove(*last);
            *selected = parent.to_vec();
        }
        TreeAction::MoveUp(p) | TreeAction::MoveDown(p) => {
            let (last, parent) = p.split_last().ok_or("the root has no siblings")?;
            let parent_node = node_at_mut(root, parent).ok_or("no such node")?;
            let n = parent_node.children.len();
            let to = match a {
                TreeAction::MoveUp(_) if *last > 0 => last - 1,
                TreeAction::MoveDown(_) if last + 1 < n => last + 1,
                _ => return Ok(()),
            };
            parent_node.children.swap(*last, to);
            *selected = parent.iter().copied().chain([to]).collect();
        }
        TreeAction::Reparent { node, parent } => {
            if node.is_empty() {
                return Err("the root cannot be moved".into());
            }
            if parent.starts_with(node) {
                return Err("a node cannot be moved into its own subtree".into());
            }
            let (last, old_parent) = node.split_last().expect("not the root");
            if old_parent == parent.as_slice() {
                return Ok(()); // already there
            }
            node_at(root, parent).ok_or("no such parent")?;
            let moved = node_at_mut(root, old_parent)
                .and_then(|p| (*last < p.children.len()).then(|| p.children.remove(*last)))
                .ok_or("no such node")?;
            // Removing the node shifts later siblings (and paths through them) down by one.
            let mut target = parent.clone();
            if target.len() > old_parent.len()
                && target.starts_with(old_parent)
                && target[old_parent.len()] > *last
            {
                target[old_parent.len()] -= 1;
            }
            let p = node_at_mut(root, &target).expect("checked above");
            p.children.push(moved);
            *selected = target
                .iter()
                .copied()
                .chain([p.children.len() - 1])
                .collect();
        }
    }
    Ok(())
}

/// Draws the tree; returns the actions asked for. Each row's place goes to the frame log
/// ([`crate::script::place`]) as `tree` `root.children[i]...`.
pub fn tree_ui(ui: &mut egui::Ui, root: &Node, selected: &NodePath) -> Vec<TreeAction> {
    let mut actions = Vec::new();
    node_row(ui, root, &mut Vec::new(), selected, &mut actions);
    actions
}

/// A node's path as written in the window and the log: `root`, `root.children[1]`, ...
pub fn path_text(p: &[usize]) -> String {
    std::iter::once("root".to_string())
        .chain(p.iter().map(|i| format!(".children[{i}]")))
        .collect()
}

/// One row: a label that selects its node when clicked, is dragged to move the node, and takes
/// a dragged node as a new child when one is dropped on it. One widget senses both the click
/// and the drag: a separate drag handle laid over the label took the clicks, so rows could not
/// be selected in the real window.
fn node_row(
    ui: &mut egui::Ui,
    n: &Node,
    path: &mut NodePath,
    selected: &NodePath,
    actions: &mut Vec<TreeAction>,
) {
    let id = egui::Id::unique(("tree node", path.clone()));
    let is_root = path.is_empty();
    let label = node_label(n, is_root);
    let header = |ui: &mut egui::Ui, actions: &mut Vec<TreeAction>| {
        let r = ui
            .selectable_label(selected == path, &label)
            .interact(egui::Sense::drag());
        crate::script::place("tree", path_text(path), &r);
        if r.clicked() {
            actions.push(TreeAction::Select(path.clone()));
        }
        if !is_root {
            r.dnd_set_drag_payload(path.clone());
        }
        if let Some(p) = r.dnd_hover_payload::<NodePath>()
            && *p != *path
        {
            ui.painter().rect_stroke(
                r.rect.expand(1.0),
                2.0,
                ui.visuals().selection.stroke,
                egui::StrokeKind::Outside,
            );
        }
        if let Some(p) = r.dnd_release_payload::<NodePath>()
            && *p != *path
        {
            actions.push(TreeAction::Reparent {
                node: (*p).clone(),
                parent: path.clone(),
            });
        }
        r.context_menu(|ui| {
            if ui.button("Add child").clicked() {
                actions.push(TreeAction::AddChild(path.clone()));
                ui.close();
            }
            if !is_root {
                for (text, a) in [
                    ("Duplicate", TreeAction::Duplicate(path.clone())),
                    ("Move up", TreeAction::MoveUp(path.clone())),
                    ("Move down", TreeAction::MoveDown(path.clone())),
                    ("Remove", TreeAction::Remove(path.clone())),
                ] {
                    if ui.button(text).clicked() {
                        actions.push(a);
                        ui.close();
                    }
                }
            }
        });
    };
    if n.children.is_empty() {
        ui.horizontal(|ui| {
            ui.add_space(18.0);
            header(ui, actions);
        });
    } else {
        egui::collapsing_header::CollapsingState::load_with_default_open(ui.ctx(), id, true)
            .show_header(ui, |ui| header(ui, actions))
            .body(|ui| {
                for (i, c) in n.children.iter().enumerate() {
                    path.push(i);
                    node_row(ui, c, path, selected, actions);
                    path.pop();
                }
            });
    }
}

/// Buttons acting on the selected node.
pub fn node_buttons(ui: &mut egui::Ui, selected: &NodePath) -> Vec<TreeAction> {
    let mut actions = Vec::new();
    ui.horizontal_wrapped(|ui| {
        if ui.button("Add child").clicked() {
            actions.push(TreeAction::AddChild(selected.clone()));
        }
        let not_root = !selected.is_empty();
        for (text, a) in [
            ("Duplicate", TreeAction::Duplicate(selected.clone())),
            ("Up", TreeAction::MoveUp(selected.clone())),
            ("Down", TreeAction::MoveDown(selected.clone())),
            ("Remove", TreeAction::Remove(selected.clone())),
        ] {
            if ui.add_enabled(not_root, egui::Button::new(text)).clicked() {
                actions.push(a);
            }
        }
    });
    actions
}

/// What an edit in a panel did, in words for the undo history (`set minor`, `add operator
/// Rotate`); `None`: nothing changed.
pub type Edit = Option<String>;

/// Keeps the first description of an edit made this frame.
pub fn keep(slot: &mut Edit, e: Edit) {
    if slot.is_none() {
        *slot = e;
    }
}

/// The inspector of one node; says what changed.
pub fn node_inspector(
    ui: &mut egui::Ui,
    n: &mut Node,
    path: &NodePath,
    notes: &mut Vec<String>,
) -> Edit {
    let mut edit = None;
    ui.push_id(("inspector", path.clone()), |ui| {
        ui.strong("Shape");
        keep(
            &mut edit,
            entry_picker::<Shape>(ui, "shape", "shape", &mut n.shape),
        );
        keep(&mut edit, call_params(ui, &mut n.shape, notes));
        if !path.is_empty() {
            ui.separator();
            ui.strong("Combine with the parent");
            keep(
                &mut edit,
                entry_picker::<Combine>(ui, "combine", "combine", &mut n.combine),
            );
            keep(&mut edit, call_params(ui, &mut n.combine, notes));
        }
        ui.separator();
        ui.strong("Domain operators (in order)");
        keep(&mut edit, call_list(ui, &mut n.ops, notes));
        ui.separator();
        ui.strong("Material");
        keep(&mut edit, material_editor(ui, &mut n.material));
    });
    edit
}

/// An ordered list of calls of family `K`: each entry's picker and parameters, with buttons to
/// move it, remove it, and add one.
fn call_list<K: Family>(
    ui: &mut egui::Ui,
    ops: &mut Vec<Call<K>>,
    notes: &mut Vec<String>,
) -> Edit {
    let mut edit = None;
    let mut remove = None;
    let mut swap = None;
    let n = ops.len();
    for (i, op) in ops.iter_mut().enumerate() {
        ui.push_id(i, |ui| {
            ui.horizontal(|ui| {
                keep(&mut edit, entry_picker::<K>(ui, "op", "operator", op));
                if ui.small_button("^").on_hover_text("earlier").clicked() && i > 0 {
                    swap = Some((i, i - 1));
                }
                if ui.small_button("v").on_hover_text("later").clicked() && i + 1 < n {
                    swap = Some((i, i + 1));
                }
                if ui.small_button("x").on_hover_text("remove").clicked() {
                    remove = Some(i);
                }
            });
            ui.indent("params", |ui| {
                keep(&mut edit, call_params(ui, op, notes));
            });
        });
    }
    if let Some((a, b)) = swap {
        let name = ops[a].kind.def().name;
        ops.swap(a, b);
        keep(
            &mut edit,
            Some(format!(
                "move operator {name} {}",
                if b < a { "earlier" } else { "later" }
            )),
        );
    }
    if let Some(i) = remove {
        let name = ops[i].kind.def().name;
        ops.remove(i);
        keep(&mut edit, Some(format!("remove operator {name}")));
    }
    if ops.len() < limits::MAX_OPS_PER_LIST {
        let mut add: Option<K> = None;
        egui::ComboBox::new(ui.scope_id().with("add op"), "")
            .selected_text("add operator...")
            .show_ui(ui, |ui| {
                for &k in K::all() {
                    if ui
                        .selectable_label(false, k.def().name)
                        .on_hover_text(k.def().doc)
                        .clicked()
                    {
                        add = Some(k);
                    }
                }
            });
        if let Some(k) = add {
            ops.push(Call::new(k));
            keep(&mut edit, Some(format!("add operator {}", k.def().name)));
        }
    }
    edit
}

/// The root's IFS loop: on or off, iterations, and its ordered operators.
pub fn ifs_editor(ui: &mut egui::Ui, ifs: &mut Option<Ifs>, notes: &mut Vec<String>) -> Edit {
    let mut edit = None;
    let mut on = ifs.is_some();
    if ui
        .checkbox(&mut on, "IFS loop around the tree")
        .on_hover_text("fold the space before the tree is evaluated, `iterations` times")
        .changed()
    {
        *ifs = on.then(|| Ifs {
            iterations: 4,
            ops: vec![Call::new(Transform::ALL[0])],
        });
        edit = Some(format!("turn the loop {}", if on { "on" } else { "off" }));
    }
    if let Some(ifs) = ifs {
        let mut it = ifs.iterations;
        let r =
            ui.add(egui::Slider::new(&mut it, 0..=limits::MAX_IFS_ITERATIONS).text("iterations"));
        crate::script::place("param", "IFS.iterations".into(), &r);
        if r.changed() {
            ifs.iterations = it;
            keep(&mut edit, Some("set iterations".into()));
        }
        ui.push_id("ifs ops", |ui| {
            keep(&mut edit, call_list(ui, &mut ifs.ops, notes));
        });
    }
    edit
}

/// A colour from an egui colour widget (f32) back to the scene's f64, written as the shortest
/// decimal that the f32 rounds to: 0.2 stays 0.2 instead of becoming 0.19999999...
pub fn colour_from_f32(c: f32) -> f64 {
    format!("{c}")
        .parse::<f64>()
        .unwrap_or(c as f64)
        .clamp(0.0, 1.0)
}

/// A colour button for the material field `name`; whether the user changed the colour. The
/// picker converts to HSVA and back every frame it is open, which moves a component by a few
/// ulps: only a change larger than that is the user's, and only such components are written.
fn colour_editor(ui: &mut egui::Ui, colour: &mut [f64; 3], name: &str) -> bool {
    let before = colour.map(|v| v as f32);
    let mut c = before;
    ui.horizontal(|ui| {
        let r = ui.color_edit_button_rgb(&mut c);
        crate::script::place("param", format!("Material.{name}"), &r);
        ui.label(name);
    });
    let mut changed = false;
    for ((dst, new), old) in colour.iter_mut().zip(c).zip(before) {
        if (new - old).abs() > 1e-5 {
            *dst = colour_from_f32(new);
            changed = true;
        }
    }
    changed
}

/// The material of a node (ranges as the scene validation checks them). Opening the colour
/// picker is not an edit: only a component the user changed is written back.
pub fn material_editor(ui: &mut egui::Ui, m: &mut Material) -> Edit {
    let mut edit = None;
    if colour_editor(ui, &mut m.albedo, "albedo") {
        edit = Some("set albedo".into());
    }
    if ui
        .add(egui::Slider::new(&mut m.specular, 0.0..=1.0).text("specular"))
        .changed()
    {
        keep(&mut edit, Some("set specular".into()));
    }
    if ui
        .add(
            egui::Slider::new(&mut m.shininess, 1.0..=4096.0)
                .logarithmic(true)
                .text("shininess"),
        )
        .changed()
    {
        keep(&mut edit, Some("set shininess".into()));
    }
    if ui
        .add(egui::Slider::new(&mut m.trap_colour, 0.0..=1.0).text("trap colour"))
        .on_hover_text("how much the orbit-trap palette replaces the albedo (fractals)")
        .changed()
    {
        keep(&mut edit, Some("set trap colour".into()));
    }
    ui.collapsing("path tracer", |ui| {
        if colour_editor(ui, &mut m.emission, "emission") {
            keep(&mut edit, Some("set emission".into()));
        }
        // The single numbers, with the ranges and texts the scene format declares.
        for name in ["emission_strength", "metallic", "transmission", "ior"] {
            let Some(f) = fathom_core::scene::fields::find(
                fathom_core::scene::fields::MATERIAL_FIELDS,
                name,
            ) else {
                continue;
            };
            let (lo, hi) = f.range.unwrap_or((0.0, 1.0));
            let fathom_core::scene::fields::Slot::Reals(v) = (f.slot)(m) else {
                continue;
            };
            let slider = egui::Slider::new(&mut v[0], lo..=hi)
                .text(name.replace('_', " "))
                .logarithmic(hi / lo.max(1e-3) >= 100.0 && name == "emission_strength");
            if ui.add(slider).on_hover_text(f.doc).changed() {
                keep(&mut edit, Some(format!("set {}", name.replace('_', " "))));
            }
        }
        let alpha = (2.0 / (m.shininess + 2.0)).sqrt();
        ui.label(format!("roughness {:.2} (from shininess)", alpha.sqrt()))
            .on_hover_text("the path tracer's GGX roughness is the shininess mapped by Walter et al.'s correspondence");
    });
    edit
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        // root(a(b), c)
        let b = Node::new(Primitive::Sphere);
        let a = Node::new(Primitive::Sphere).child(b);
        let c = Node::new(Primitive::Sphere);
        Scene::new(Node::new(Primitive::Sphere).child(a).child(c))
    }

    #[test]
    fn tree_edits_keep_the_selection_on_the_edited_node() {
        let mut s = scene();
        let mut sel = vec![];
        apply(&mut s, &TreeAction::AddChild(vec![1]), &mut sel).unwrap();
        assert_eq!(sel, vec![1, 0]);
        assert_eq!(s.root.count(), 5);
        apply(&mut s, &TreeAction::Duplicate(vec![0]), &mut sel).unwrap();
        assert_eq!((sel.clone(), s.root.children.len()), (vec![1], 3));
        assert_eq!(s.root.count(), 7);
        apply(&mut s, &TreeAction::MoveDown(vec![0]), &mut sel).unwrap();
        assert_eq!(sel, vec![1]);
        apply(&mut s, &TreeAction::Remove(vec![1]), &mut sel).unwrap();
        assert_eq!((sel, s.root.count()), (vec![], 5));
        assert!(apply(&mut s, &TreeAction::Remove(vec![]), &mut vec![]).is_err());
    }

    #[test]
    fn reparenting_moves_subtrees_and_refuses_cycles() {
        let mut s = scene();
        let mut sel = vec![];
        // Move c (root.children[1]) under a (root.children[0]).
        apply(
            &mut s,
            &TreeAction::Reparent {
                node: vec![1],
                parent: vec![0],
            },
            &mut sel,
        )
        .unwrap();
        assert_eq!(s.root.children.len(), 1);
        assert_eq!(s.root.children[0].children.len(), 2);
        assert_eq!(sel, vec![0, 1]);
        // Moving a into its own child is refused and changes nothing.
        let before = s.clone();
        let e = apply(
            &mut s,
            &TreeAction::Reparent {
                node: vec![0],
                parent: vec![0, 0],
            },
            &mut sel,
        )
        .unwrap_err();
        assert!(e.contains("own subtree"), "{e}");
        assert_eq!(s, before);
        // Moving an earlier sibling's subtree under a later sibling fixes up the path.
        let mut s = scene();
        apply(
            &mut s,
            &TreeAction::Reparent {
                node: vec![0],
                parent: vec![1],
            },
            &mut sel,
        )
        .unwrap();
        assert_eq!(sel, vec![0, 0]);
        assert_eq!(s.root.children[0].children[0].children.len(), 1);
        s.validate().unwrap();
    }
}
