//! Nodes and transforms: the whole-graph check (dangling children, cycles), choosing the scene's root nodes,
//! and instantiating the node hierarchy with its world transforms.

use super::{json, quoted, Loader, Res, MAX_DEPTH, MAX_NODE_VISITS};
use crate::scene::LoadOptions;
use glam::{Mat4, Quat, Vec3};

/// Checks the whole node graph before anything is instantiated: every child index exists, and no node is its
/// own ancestor. Nodes that no scene uses are checked too (a cycle makes the file invalid wherever it is), and
/// the error shows the cycle. Iterative, so arbitrarily deep (valid) hierarchies cannot overflow the stack.
pub(super) fn check_node_graph(root: &json::Root) -> Res<()> {
    let nodes = &root.nodes;
    let label = |i: usize| format!("node {i}{}", quoted(&nodes[i].name));
    // 0 = not visited, 1 = on the current path, 2 = done.
    let mut state = vec![0u8; nodes.len()];
    for start in 0..nodes.len() {
        if state[start] != 0 {
            continue;
        }
        // (node, index of the next child to visit)
        let mut stack = vec![(start, 0usize)];
        state[start] = 1;
        while let Some(top) = stack.last_mut() {
            let (node, next) = *top;
            let children = nodes[node].children.as_deref().unwrap_or(&[]);
            let Some(child) = children.get(next).map(|c| c.value()) else {
                state[node] = 2;
                stack.pop();
                continue;
            };
            top.1 += 1;
            if child >= nodes.len() {
                let count = nodes.len();
                return Err(format!("{}: child node {child} does not exist (the file has {count} nodes)", label(node)));
            }
            match state[child] {
                0 => {
                    state[child] = 1;
                    stack.push((child, 0));
                }
                1 => {
                    let from = stack.iter().position(|&(n, _)| n == child).unwrap_or(0);
                    let path: Vec<String> =
                        stack[from..].iter().map(|&(n, _)| n.to_string()).chain([child.to_string()]).collect();
                    return Err(format!(
                        "{} is its own ancestor: the node hierarchy contains a cycle (nodes {})",
                        label(child),
                        path.join(" → ")
                    ));
                }
                _ => {}
            }
        }
    }
    Ok(())
}

impl Loader<'_> {
    /// The root nodes to instantiate: the requested scene, the default one, scene 0, or (no scenes) all
    /// parentless nodes.
    pub(super) fn scene_roots(&mut self, options: &LoadOptions) -> Res<Vec<usize>> {
        let scenes = &self.root.scenes;
        let index = match (options.gltf_scene, self.root.scene) {
            (Some(i), _) => i,
            (None, _) if scenes.is_empty() => return Ok(self.orphan_roots()),
            (None, Some(i)) => i.value(),
            (None, None) => {
                self.notes.push("the file names no default scene; using scene 0".into());
                0
            }
        };
        let scene = scenes.get(index).ok_or_else(|| {
            let source = if options.gltf_scene.is_some() { "was requested" } else { "is the default scene" };
            format!("scene {index} {source}, but the file has {} scene(s)", scenes.len())
        })?;
        Ok(scene.nodes.iter().map(|n| n.value()).collect())
    }

    /// Without scenes the spec leaves the content undefined; rendering every parentless node is the
    /// most useful reading (and says so).
    fn orphan_roots(&mut self) -> Vec<usize> {
        let mut is_child = vec![false; self.root.nodes.len()];
        for child in self.root.nodes.iter().flat_map(|n| n.children.iter().flatten()) {
            if let Some(flag) = is_child.get_mut(child.value()) {
                *flag = true;
            }
        }
        let roots: Vec<usize> = (0..is_child.len()).filter(|&i| !is_child[i]).collect();
        match roots.len() {
            0 => self.notes.push("the file has no scenes".into()),
            n => self.notes.push(format!("the file has no scenes; instantiating all {n} root node(s)")),
        }
        roots
    }

    /// Instantiates node `index` and its subtree under the `parent` transform.
    pub(super) fn visit(&mut self, index: usize, parent: &Mat4, on_path: &mut [bool], depth: usize) -> Res<()> {
        let root = self.root;
        let count = root.nodes.len();
        let node =
            root.nodes.get(index).ok_or_else(|| format!("node {index} does not exist (the file has {count} nodes)"))?;
        let label = format!("node {index}{}", quoted(&node.name));
        if on_path[index] {
            return Err(format!("{label} is its own ancestor: the node hierarchy contains a cycle"));
        }
        if depth >= MAX_DEPTH {
            return Err(format!("{label}: the node hierarchy is deeper than {MAX_DEPTH} levels"));
        }
        self.visits += 1;
        if self.visits > MAX_NODE_VISITS {
            return Err(format!(
                "the scene expands to more than {MAX_NODE_VISITS} node instances (nodes shared by many parents?)"
            ));
        }
        let world = *parent * local_transform(node).map_err(|m| format!("{label}: {m}"))?;
        self.place_node(node, &label, &world)?;
        on_path[index] = true;
        for child in node.children.iter().flatten() {
            self.visit(child.value(), &world, on_path, depth + 1)?;
        }
        on_path[index] = false;
        Ok(())
    }

    /// Adds what a node carries: mesh primitives, a camera, a punctual light.
    fn place_node(&mut self, node: &json::Node, label: &str, world: &Mat4) -> Res<()> {
        if let Some(mesh) = node.mesh {
            if node.skin.is_some() {
                self.notes
                    .once("skin", || "skinning is ignored: skinned meshes are rendered in their bind pose".into());
            }
            self.place_mesh(mesh.value(), world)?;
        }
        // Every camera is checked (so that skipped ones are reported); the first usable one wins.
        if let Some(camera) = node.camera {
            let camera = self.camera(camera.value(), world)?;
            self.camera = self.camera.take().or(camera);
        }
        let light = node.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        if let Some(light) = light {
            self.light(light.light.value(), world, label)?;
        }
        Ok(())
    }
}

/// A node's local transform from its matrix or its translation / rotation / scale.
fn local_transform(node: &json::Node) -> Res<Mat4> {
    let matrix = match node.matrix {
        Some(m) => Mat4::from_cols_array(&m),
        None => {
            let rotation = Quat::from_array(node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r.0));
            let length = rotation.length();
            if !(length.is_finite() && length > 1e-6) {
                return Err(format!("rotation {rotation} is not a valid quaternion"));
            }
            let scale = Vec3::from(node.scale.unwrap_or([1.0; 3]));
            let translation = Vec3::from(node.translation.unwrap_or([0.0; 3]));
            Mat4::from_scale_rotation_translation(scale, rotation / length, translation)
        }
    };
    if !matrix.is_finite() {
        return Err("the transform contains non-finite values".into());
    }
    Ok(matrix)
}
