//! Baked geometry: a tiny scene's primitives written into the render shader as literals.
//!
//! For scenes of at most `FLAT_MAX_PRIMS` primitives (`Features::flat`) traversal is a generated, unrolled list of
//! intersection tests with the geometry as constants. Why it pays on lavapipe: the driver runs shader code under
//! SIMD masks, so the cost of a trace is the length of its code, whatever the rays do; generated code can be
//! shorter than any loop over buffers:
//! - no loads (every storage-buffer read is a bounds-checked gather), and per-primitive invariants folded into
//!   literals (a quad's normal and dual axes);
//! - triangles of a mesh share vertices and edges, and the watertight test's per-ray work is per vertex (shear)
//!   and per edge (edge function): each distinct vertex and edge is computed once per ray and shared by the
//!   triangles around it — the same values, bit for bit, as testing each triangle alone (`tri_hit`).
//!
//! The storage buffers stay bound: shading (`surface_at`) reads them once per hit, and the generic pipeline (the
//! viewer's) never calls the baked function.

use crate::accel::bvh;
use crate::accel::convex_solids::convex_solids;
use crate::gpu::types::*;
use crate::render::scene_data::SceneData;
use glam::Vec3;
use std::collections::HashMap;
use std::fmt::Write;

pub use crate::render::scene_data::FLAT_MAX_PRIMS;

/// (triangles, spheres, quads) of a scene small enough to test every primitive without a BVH.
pub fn flat_counts(data: &SceneData) -> Option<(u32, u32, u32)> {
    let n = (data.tri_shading.len(), data.spheres.len(), data.quads.len());
    (n.0 + n.1 + n.2 <= FLAT_MAX_PRIMS).then_some((n.0 as u32, n.1 as u32, n.2 as u32))
}

/// A WGSL f32 literal that round-trips exactly (Rust's shortest representation, with the `f` suffix).
///
/// WGSL has no literal for an infinity or a NaN (`inf.0f` fails to validate): a non-finite value is never written.
/// The loaders refuse them (`scene::check_finite`), so one here is a bug upstream; it is logged and written as the
/// nearest finite value (±f32::MAX, and 0 for NaN) so that the shader still validates.
fn lit(x: f32) -> String {
    let x = if x.is_finite() {
        x
    } else {
        log::error!("baked shader: non-finite value {x} written as a finite literal (a scene value escaped checks)");
        debug_assert!(false, "non-finite value {x} in a baked shader literal");
        if x.is_nan() {
            0.0
        } else {
            f32::MAX.copysign(x)
        }
    };
    let s = format!("{x:?}");
    if s.contains(['.', 'e', 'E']) {
        format!("{s}f")
    } else {
        format!("{s}.0f")
    }
}

fn vec3_lit(v: Vec3) -> String {
    format!("vec3<f32>({}, {}, {})", lit(v.x), lit(v.y), lit(v.z))
}

/// Distinct vertices (by bit pattern) and undirected edges of the triangles, in first-use order.
struct MeshTopology {
    vertices: Vec<Vec3>,
    /// Per triangle: its three vertex ids.
    corners: Vec<[usize; 3]>,
    /// Undirected edges (lower id first).
    edges: Vec<(usize, usize)>,
    edge_id: HashMap<(usize, usize), usize>,
}

impl MeshTopology {
    fn of(tri_verts: &[[f32; 4]], n: usize) -> MeshTopology {
        let mut t = MeshTopology { vertices: vec![], corners: vec![], edges: vec![], edge_id: HashMap::new() };
        let mut vertex_id: HashMap<[u32; 3], usize> = HashMap::new();
        for tri in 0..n {
            let mut c = [0; 3];
            for (k, id) in c.iter_mut().enumerate() {
                let p = tri_verts[3 * tri + k];
                let key = [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()];
                *id = *vertex_id.entry(key).or_insert_with(|| {
                    t.vertices.push(Vec3::new(p[0], p[1], p[2]));
                    t.vertices.len() - 1
                });
            }
            for (a, b) in [(c[2], c[1]), (c[0], c[2]), (c[1], c[0])] {
                let key = (a.min(b), a.max(b));
                if !t.edge_id.contains_key(&key) {
                    t.edge_id.insert(key, t.edges.len());
                    t.edges.push(key);
                }
            }
            t.corners.push(c);
        }
        t
    }

    /// The WGSL expression for the edge function from vertex `a` to `b`: the shared edge value, negated when the
    /// edge is stored the other way round (tri_edge(q, p) = −tri_edge(p, q) exactly: same canonical product).
    fn edge_expr(&self, a: usize, b: usize) -> String {
        let id = self.edge_id[&(a.min(b), a.max(b))];
        if a < b {
            format!("e{id}")
        } else {
            format!("-e{id}")
        }
    }
}

/// The member types of WGSL struct `name` in shaders/common.wgsl, in order, read from the shader source itself
/// so that the literals written here can never fall out of step with the struct (whose layout matches its Rust
/// twin: tests/layout.rs). One member per line, `name: type,` with an optional `//` comment, as common.wgsl
/// writes them.
fn wgsl_members(name: &str) -> Vec<String> {
    let source = crate::render::shaders::file("common.wgsl");
    let head = format!("struct {name} {{");
    let body =
        source.split_once(&head).map(|(_, rest)| rest).unwrap_or_else(|| panic!("no struct {name} in common.wgsl"));
    let body = &body[..body.find('}').expect("struct body closed")];
    body.lines()
        .map(|l| l.split("//").next().unwrap_or("").trim())
        .filter(|l| !l.is_empty())
        .map(|l| l.split_once(':').expect("member `name: type,`").1.trim().trim_end_matches(',').trim().to_string())
        .collect()
}

/// A WGSL constructor `name(...)` for one struct given as 4-byte words, or None if a float is not finite (WGSL
/// has no literal for it; that table is then read from its buffer).
fn struct_lit(name: &str, members: &[String], words: &[u32]) -> Option<String> {
    let mut args = vec![];
    let mut w = words.iter();
    for ty in members {
        let (n, scalar) = match ty.as_str() {
            "f32" | "u32" => (1, ty.as_str()),
            t => (t[3..4].parse::<usize>().ok()?, &t[5..8]),
        };
        let mut parts = vec![];
        for _ in 0..n {
            let x = *w.next()?;
            parts.push(if scalar == "f32" {
                let f = f32::from_bits(x);
                if !f.is_finite() {
                    return None;
                }
                lit(f)
            } else {
                format!("{x}u")
            });
        }
        args.push(if n == 1 { parts.remove(0) } else { format!("{ty}({})", parts.join(", ")) });
    }
    Some(format!("{name}({})", args.join(", ")))
}

/// `fn accessor(i: u32) -> ty` returning entry i of `items` through a chain of selections (i out of range gives
/// entry 0, as a clamped buffer read would give some entry), or reading `buffer_read` when an entry cannot be
/// written as literals or there is none.
fn accessor<T: bytemuck::Pod>(name: &str, ty: &str, members: &[String], items: &[T], buffer_read: &str) -> String {
    literal_accessor(name, ty, members, items, buffer_read, false)
}

/// `accessor`, or with `buffer_beyond` one that reads `buffer_read` for i ≥ items.len() (where a table's first
/// entries are few and read often: a scene's lamps before their faces).
fn literal_accessor<T: bytemuck::Pod>(
    name: &str,
    ty: &str,
    members: &[String],
    items: &[T],
    buffer_read: &str,
    buffer_beyond: bool,
) -> String {
    let lits: Option<Vec<String>> =
        items.iter().map(|x| struct_lit(ty, members, bytemuck::cast_slice(std::slice::from_ref(x)))).collect();
    match lits {
        Some(l) if !l.is_empty() => {
            let mut f = format!("fn {name}(i: u32) -> {ty} {{\n");
            if buffer_beyond {
                let _ = writeln!(f, "    if i >= {}u {{ return {buffer_read}; }}", l.len());
            }
            let _ = writeln!(f, "    var x = {};", l[0]);
            for (k, e) in l.iter().enumerate().skip(1) {
                let _ = writeln!(f, "    if (i == {k}u) {{ x = {e}; }}");
            }
            f + "    return x;\n}\n"
        }
        _ => format!("fn {name}(i: u32) -> {ty} {{ return {buffer_read}; }}\n"),
    }
}

/// The generated `scene_data.wgsl` and `baked_geometry.wgsl` for `data` (the shader files of those names are the
/// stubs: they list the functions to define), or None when the scene is too large to bake (`Features::flat`).
pub fn scene_data_source(data: &SceneData) -> Option<(String, String)> {
    flat_counts(data)?;
    let mut out = String::from(
        "// scene_data.wgsl, generated for one scene by src/render/baked.rs: its tables as literals.\n\n\
         struct TriPositions {\n    v0: vec3<f32>,\n    v1: vec3<f32>,\n    v2: vec3<f32>,\n    corners: vec3<u32>,\n}\n\n",
    );
    // Positions as f32 bits, then the corners' shading-vertex indices (the layout of scene_data.wgsl's struct).
    let positions: Vec<[u32; 12]> = (0..data.tri_shading.len())
        .map(|i| {
            let v = |k: usize| data.tri_vertex(3 * i + k).map(f32::to_bits);
            let (a, b, c, s) = (v(0), v(1), v(2), data.tri_shading[i].corners);
            [a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], s[0], s[1], s[2]]
        })
        .collect();
    // The buffer's w words count shading records, not vertices: the corners come from the (always literal) records.
    let tri_read = "TriPositions(tri_position(3u * i), tri_position(3u * i + 1u), tri_position(3u * i + 2u), \
                    scene_tri_record(i).corners)";
    let members = ["vec3<f32>", "vec3<f32>", "vec3<f32>", "vec3<u32>"].map(String::from);
    out += &accessor("scene_tri_positions", "TriPositions", &members, &positions, tri_read);
    // Every TriShading member is a u32, so this table is always literals (no buffer fallback is ever used).
    let shading = wgsl_members("TriShading");
    out +=
        &accessor("scene_tri_record", "TriShading", &shading, &data.tri_shading, "TriShading(vec3<u32>(0u), INVALID)");
    out += "fn scene_tri_corner(i: u32, k: u32) -> u32 { return scene_tri_record(i).corners[k]; }\n\
            fn scene_tri_light(i: u32) -> u32 { return scene_tri_record(i).light; }\n";
    let vertex = wgsl_members("ShadingVertex");
    // Indexed by vertex here (the corners above are `tri_shading`'s); the buffer holds `stride` records per vertex.
    let stride = data.shading_record_stride();
    let uv = if stride == 2 { "bitcast<vec2<f32>>(load_shading_verts(2u * i + 1u))" } else { "vec2<f32>(0.0)" };
    let read = format!("ShadingVertex(load_shading_verts({stride}u * i).x, load_shading_verts({stride}u * i).y, {uv})");
    out += &accessor("scene_shading_vertex", "ShadingVertex", &vertex, &data.shading_verts, &read);
    out += &accessor("scene_sphere", "Sphere", &wgsl_members("Sphere"), &data.spheres, "load_spheres(i)");
    out += &accessor("scene_quad", "Quad", &wgsl_members("Quad"), &data.quads, "load_quads(i)");
    out += &accessor("scene_material", "Material", &wgsl_members("Material"), &data.materials, "load_materials(i)");
    out += &accessor("scene_light", "Light", &wgsl_members("Light"), &data.lights, "load_lights(i)");
    // (No BVH is walked, but the wide traversal that is compiled out still names the root functions.)
    Some((out, baked_traverse_source(data, 0..data.tri_shading.len(), true) + BUFFER_ROOT))
}

/// Most materials, and most lights that selection chooses among, a scene with baked occluders has as literals.
const LITERAL_TABLE_MAX: usize = 32;

/// The generated `scene_data.wgsl` of a scene with baked occluders: the buffer-reading one with the materials and
/// the lights that selection chooses among (its few lamps, not their faces) as literals when they are few.
pub fn occluder_scene_data_source(data: &SceneData) -> Option<String> {
    baked_occluders(data).then_some(())?;
    let mut out = crate::render::shaders::file("scene_data.wgsl").to_string();
    if data.materials.len() <= LITERAL_TABLE_MAX {
        let f = accessor("scene_material", "Material", &wgsl_members("Material"), &data.materials, "load_materials(i)");
        out = out.replace("fn scene_material(i: u32) -> Material { return load_materials(i); }\n", &f);
    }
    let n = data.selectable_lights();
    if n <= LITERAL_TABLE_MAX {
        let f =
            literal_accessor("scene_light", "Light", &wgsl_members("Light"), &data.lights[..n], "load_lights(i)", true);
        out = out.replace("fn scene_light(i: u32) -> Light { return load_lights(i); }\n", &f);
    }
    // The occluders' positions, corners (record indices, as the buffer's w words hold them) and shading records:
    // what shading a hit on one reads.
    let (first, count) = (data.occluders.0 as usize, data.occluders.1 as usize);
    let words = |i: usize, k: usize| data.tri_vertex(3 * i + k).map(f32::to_bits);
    let positions: Vec<[u32; 12]> = (first..first + count)
        .map(|i| {
            let (a, b, c) = (words(i, 0), words(i, 1), words(i, 2));
            [a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], a[3], b[3], c[3]]
        })
        .collect();
    let members = ["vec3<f32>", "vec3<f32>", "vec3<f32>", "vec3<u32>"].map(String::from);
    out += &accessor("occluder_tri_positions", "TriPositions", &members, &positions, "TriPositions()");
    let (f, c) = (first, count);
    let inject = |out: String, head: &str, body: &str| {
        assert!(out.contains(head), "scene_data.wgsl has `{head}`");
        out.replace(head, &format!("{head}\n    if i - {f}u < {c}u {{ {body} }}"))
    };
    out = inject(
        out,
        "fn scene_tri_positions(i: u32) -> TriPositions {",
        &format!("return occluder_tri_positions(i - {f}u);"),
    );
    out = inject(
        out,
        "fn scene_tri_corner(i: u32, k: u32) -> u32 {",
        &format!("return occluder_tri_positions(i - {f}u).corners[k];"),
    );
    out = inject(out, "fn scene_tri_light(i: u32) -> u32 {", "return INVALID;");
    if data.shading_record_stride() == 1 {
        let mut records: Vec<u32> = positions.iter().flat_map(|p| [p[9], p[10], p[11]]).collect();
        records.sort_unstable();
        records.dedup();
        let mut body = String::from("var hit = false;\n    var x = ShadingVertex(0u, 0u, vec2<f32>(0.0));\n");
        for r in records {
            let [n, m] = data.shading_records[r as usize];
            let _ =
                writeln!(body, "    if (r == {r}u) {{ x = ShadingVertex({n}u, {m}u, vec2<f32>(0.0)); hit = true; }}");
        }
        body += "    if hit { return x; }";
        let head = "fn scene_shading_vertex(r: u32) -> ShadingVertex {";
        assert!(out.contains(head));
        out = out.replace(head, &format!("{head}\n    {body}"));
    }
    Some(out)
}

/// Whether `data`'s pipelines bake its occluders (`SceneData::occluders`; a scene baked whole needs no split).
pub fn baked_occluders(data: &SceneData) -> bool {
    data.occluders.1 > 0 && flat_counts(data).is_none()
}

/// Whether `data`'s own pipelines test its wide BVH's root children against their exact boxes, as literals
/// (`baked_root_source`), instead of loading the root node: one node load less per ray, and exact boxes instead of
/// 8-bit ones rounded outwards by up to 1/255 of the root's extent per axis — in a scene whose root spans a large
/// floor around a small object, each of the object's subtrees is entered by rays that pass well beside it
/// (docs/profile-bvh.md, "The root as literals"). Always with baked occluders, where the root stops a ray at a
/// lamp's exact box.
pub fn baked_root(data: &SceneData) -> bool {
    flat_counts(data).is_none() && !data.wide_nodes.is_empty() && (data.baked_root || baked_occluders(data))
}

/// The generated `baked_geometry.wgsl` of a BVH scene whose root alone is baked (`baked_root`, no baked
/// occluders): nothing to test before the BVH, and the root's boxes as literals. None otherwise.
pub fn root_source(data: &SceneData) -> Option<String> {
    if !baked_root(data) || baked_occluders(data) {
        return None;
    }
    Some(String::from(NO_BAKED_PRIMITIVES) + &baked_root_source(data, &data.wide_nodes[0]))
}

/// baked_geometry.wgsl's primitive tests in a pipeline that has no baked primitives (FLAT_SCENE and
/// BAKED_OCCLUDERS are false there, so nothing calls them; they only have to exist).
const NO_BAKED_PRIMITIVES: &str =
    "// baked_geometry.wgsl, generated for one scene by src/render/baked.rs: its BVH root's boxes.

fn baked_traverse(r: TraceRay, start: Hit, skip: u32) -> Hit {
    return start;
}

fn baked_occluded(r: TraceRay, t_max: f32, skip: u32) -> bool {
    return false;
}
";

/// The root functions of baked_geometry.wgsl as they read the wide BVH's root node from its buffer.
const BUFFER_ROOT: &str = "
fn baked_wide_root() -> WideNode {
    return wide_node(0u);
}

fn baked_root_hits(r: TraceRay, oct: u32, t: f32) -> u32 {
    return wide_node_hits(r, oct, wide_node(0u), t);
}
";

/// `baked_wide_root` (the root node's links as literals) and `baked_root_hits`: the root's children tested
/// against their exact f32 boxes, as literals. Exact, not the node's 8-bit boxes: those are rounded outwards by up
/// to 1/255 of the root's extent, far more than a small lamp's size, so a shadow ray stopping at a lamp's box would
/// still enter the lamp's subtree.
fn baked_root_source(data: &SceneData, root: &crate::accel::wide_bvh::GpuWideNode) -> String {
    use crate::accel::wide_bvh::{WideChild, WIDTH};
    let w: &[u32] = bytemuck::cast_slice(std::slice::from_ref(root));
    let v = |k: usize| format!("vec4<u32>({}u, {}u, {}u, {}u)", w[4 * k], w[4 * k + 1], w[4 * k + 2], w[4 * k + 3]);
    let mut out = format!(
        "\nfn baked_wide_root() -> WideNode {{\n    return WideNode({}, {}, {}, {}, {});\n}}\n",
        v(0),
        v(1),
        v(2),
        v(3),
        v(4)
    );
    // The box of leaf-order entries first..first + count: each entry's primitive (the reference itself where the
    // leaf order is the triangle order) bounded as the BVH build bounds it — a triangle by its f32 vertices, which
    // the traversal tests, a sphere or quad rounded outwards.
    let identity = data.prim_refs == crate::render::scene_data::IDENTITY_PRIM_REFS;
    let leaf_box = |first: u32, count: u32, b: &mut (Vec3, Vec3)| {
        for j in first..first + count {
            let prim = if identity { make_prim(PRIM_TRIANGLE, j) } else { data.prim_refs[j as usize] };
            let i = (prim & PRIM_INDEX_MASK) as usize;
            let bounds = match prim >> PRIM_KIND_SHIFT {
                PRIM_TRIANGLE => {
                    let p = |k: usize| Vec3::from_slice(&data.tri_vertex(3 * i + k)[..3]);
                    bvh::triangle_aabb(&[p(0), p(1), p(2)])
                }
                PRIM_SPHERE => bvh::sphere_aabb(&data.spheres[i]),
                _ => bvh::quad_aabb(&data.quads[i]),
            };
            // Every entry in a leaf has a box (the build leaves out the primitives that have none).
            if let Some(a) = bounds {
                b.0 = b.0.min(a.min);
                b.1 = b.1.max(a.max);
            }
        }
    };
    out += "\nfn baked_root_hits(r: TraceRay, oct: u32, t: f32) -> u32 {\n    var hits = 0u;\n";
    for slot in 0..WIDTH {
        let mut b = (Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
        let bits = match root.child(slot) {
            WideChild::Empty => continue,
            WideChild::Leaf { first, count } => {
                leaf_box(first, count, &mut b);
                ((1u32 << count) - 1) << (root.meta(slot) & 31)
            }
            WideChild::Interior(node) => {
                let mut todo = vec![node];
                while let Some(n) = todo.pop() {
                    let n = &data.wide_nodes[n as usize];
                    for s in 0..WIDTH {
                        match n.child(s) {
                            WideChild::Empty => {}
                            WideChild::Leaf { first, count } => leaf_box(first, count, &mut b),
                            WideChild::Interior(c) => todo.push(c),
                        }
                    }
                }
                // The visiting rank's bit: slot ^ oct, computed in the shader.
                0
            }
        };
        // Within the node's own (conservative) 8-bit box as well: a pre-split triangle's entry stands for the piece
        // inside that box (`accel::presplit`), and its whole triangle may reach far beyond it.
        let q = root.child_box(slot);
        b = (b.0.max(q.min), b.1.min(q.max));
        let hit_bits = if bits == 0 { format!("1u << (24u + ({slot}u ^ oct))") } else { format!("{bits}u") };
        let _ = writeln!(
            out,
            "    hits |= select(0u, {hit_bits}, ray_box_entry(r, {}, {}, t) != F32_MAX);",
            vec3_lit(b.0),
            vec3_lit(b.1)
        );
    }
    out + "    return hits;\n}\n"
}

/// The generated `light_tree_loads.wgsl` of a scene with baked occluders and a light tree of at most
/// `LITERAL_TABLE_MAX` nodes (its few lamps): every node a literal. None otherwise.
pub fn occluder_light_tree_source(data: &SceneData) -> Option<String> {
    baked_occluders(data).then_some(())?;
    let n = data.light_tree.len();
    if n == 0 || n > LITERAL_TABLE_MAX {
        return None;
    }
    let members = ["vec4<u32>"; 4].map(String::from);
    Some(accessor("light_node", "LightNode", &members, &data.light_tree, "load_light_tree(i)"))
}

/// The generated `baked_geometry.wgsl` of a scene with baked occluders (`SceneData::occluders`): the tests of
/// those triangles alone, run before the BVH; None when the scene has none (or is baked whole).
pub fn occluder_source(data: &SceneData) -> Option<String> {
    if !baked_occluders(data) {
        return None;
    }
    let (first, count) = (data.occluders.0 as usize, data.occluders.1 as usize);
    let mut out = baked_traverse_source(data, first..first + count, false);
    out += &match data.wide_nodes.first() {
        Some(root) => baked_root_source(data, root),
        None => BUFFER_ROOT.into(),
    };
    Some(out)
}

/// `baked_traverse` (closest hit) and `baked_occluded` (shadow rays) for `data`'s triangles `tris` (slots of the
/// per-triangle arrays) and, with `analytic`, every sphere and quad: each primitive's test with its data as literals.
fn baked_traverse_source(data: &SceneData, tris: std::ops::Range<usize>, analytic: bool) -> String {
    let mut out = String::from(
        "// baked_geometry.wgsl, generated for one scene by src/render/baked.rs: every intersection test, unrolled.\n\n\
         fn baked_traverse(r: TraceRay, start: Hit, skip: u32) -> Hit {\n    var hit = start;\n",
    );
    primitive_tests(data, &mut out, Query::Closest, tris.clone(), analytic);
    out += "    return hit;\n}\n\n\
            fn baked_occluded(r: TraceRay, t_max: f32, skip: u32) -> bool {\n    var occluded = false;\n";
    primitive_tests(data, &mut out, Query::Occluded, tris, analytic);
    out += "    return occluded;\n}\n";
    out
}

/// What a generated traversal computes.
#[derive(Clone, Copy, PartialEq)]
enum Query {
    /// The closest hit, into `hit`.
    Closest,
    /// Whether anything but `skip` blocks (0, t_max), into `occluded`.
    Occluded,
}

/// Appends the tests for `query` of triangles `tris` and, with `analytic`, of every sphere and quad.
fn primitive_tests(data: &SceneData, out: &mut String, query: Query, tris: std::ops::Range<usize>, analytic: bool) {
    let first = tris.start;
    // The triangles' vertices, wherever they are (a scene's occluders follow its BVH's triangles, which may span
    // several vertex bindings).
    let verts: Vec<[f32; 4]> = (3 * first..3 * tris.end).map(|k| data.tri_vertex(k)).collect();
    let mesh = MeshTopology::of(&verts, tris.len());
    // Each vertex and edge is emitted just before the first triangle that needs it, so fewer values are live
    // at once (spilling them costs more than recomputing would).
    let (mut have_v, mut have_e) = (vec![false; mesh.vertices.len()], vec![false; mesh.edges.len()]);
    // Shadow rays test closed convex meshes (not lights) as solids: a few plane clips instead of their triangles.
    let solids = match query {
        Query::Occluded => convex_solids(&verts, tris.len(), |t| data.tri_shading[first + t].light != INVALID),
        Query::Closest => vec![],
    };
    let in_solid: Vec<bool> =
        (0..mesh.corners.len()).map(|t| solids.iter().any(|s| s.triangles.contains(&t))).collect();
    for (i, [a, b, c]) in mesh.corners.iter().enumerate() {
        if in_solid[i] {
            continue;
        }
        for v in [*a, *b, *c] {
            if !std::mem::replace(&mut have_v[v], true) {
                let _ = writeln!(out, "    let v{v} = tri_vertex(r, {});", vec3_lit(mesh.vertices[v]));
            }
        }
        for (p, q) in [(*c, *b), (*a, *c), (*b, *a)] {
            let id = mesh.edge_id[&(p.min(q), p.max(q))];
            if !std::mem::replace(&mut have_e[id], true) {
                let (x, y) = mesh.edges[id];
                let _ = writeln!(out, "    let e{id} = tri_edge(v{x}.xy, v{y}.xy);");
            }
        }
        let (u, v, w) = (mesh.edge_expr(*c, *b), mesh.edge_expr(*a, *c), mesh.edge_expr(*b, *a));
        let call = format!("tri_hit({u}, {v}, {w}, v{a}.z, v{b}.z, v{c}.z, T_MAX)");
        test_prim(out, query, make_prim(PRIM_TRIANGLE, (first + i) as u32), &call);
    }
    for s in &solids {
        out.push_str("    {\n        var span = vec2<f32>(0.0, t_max);\n");
        for (n, d) in &s.planes {
            let _ = writeln!(
                out,
                "        span = clip_to_half_space(span, r, {}, {});",
                vec3_lit(n.as_vec3()),
                lit(*d as f32)
            );
        }
        let _ =
            writeln!(out, "        occluded = occluded | (span.x < span.y); // triangles {:?}\n    }}", s.triangles);
    }
    if !analytic {
        return;
    }
    for (i, s) in data.spheres.iter().enumerate() {
        let call = format!("intersect_sphere(r.o, r.d, {}, {}, T_MAX)", vec3_lit(s.center.into()), lit(s.radius));
        test_prim(out, query, make_prim(PRIM_SPHERE, i as u32), &call);
    }
    for (i, q) in data.quads.iter().enumerate() {
        let (eu, ev) = (Vec3::from(q.edge_u), Vec3::from(q.edge_v));
        let n = eu.cross(ev);
        let inv_nn = 1.0 / n.dot(n);
        if !(inv_nn.is_finite() && n.is_finite()) {
            continue; // degenerate: `intersect_quad` never reports a hit for it either
        }
        let call = format!(
            "intersect_parallelogram(r.o, r.d, {}, {}, {}, {}, T_MAX)",
            vec3_lit(q.corner.into()),
            vec3_lit(n),
            vec3_lit(ev.cross(n) * inv_nn),
            vec3_lit(n.cross(eu) * inv_nn)
        );
        test_prim(out, query, make_prim(PRIM_QUAD, i as u32), &call);
    }
}

/// One primitive's test: `call` (with T_MAX for the ray's current extent) yields the (t, b1, b2, hit) vector.
/// Selects, no branches: lavapipe executes a branch's body whether or not a lane takes it, plus mask upkeep; and
/// an early return for shadow rays saves nothing there.
fn test_prim(out: &mut String, query: Query, prim: u32, call: &str) {
    let _ = match query {
        Query::Closest => writeln!(
            out,
            "    {{ let h = {}; let take = h.w != 0.0 && skip != {prim}u; \
             hit = Hit(select(hit.t, h.x, take), select(hit.prim, {prim}u, take), select(hit.b1, h.y, take), select(hit.b2, h.z, take)); }}",
            call.replace("T_MAX", "hit.t")
        ),
        Query::Occluded => {
            writeln!(out, "    occluded = occluded | (({}).w != 0.0 && skip != {prim}u);", call.replace("T_MAX", "t_max"))
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No literal is ever an infinity or a NaN, which WGSL cannot spell.
    #[test]
    #[cfg(not(debug_assertions))]
    fn literals_are_always_finite() {
        assert_eq!(lit(f32::INFINITY), "3.4028235e38f");
        assert_eq!(lit(f32::NEG_INFINITY), "-3.4028235e38f");
        assert_eq!(lit(f32::NAN), "0.0f");
        assert_eq!(lit(1.5), "1.5f");
        assert_eq!(lit(2.0), "2.0f");
    }

    /// The member lists read from common.wgsl cover every 4-byte word of the Rust twins (no padding words
    /// exist in these structs: their vec3s are followed by a scalar).
    #[test]
    fn member_lists_cover_the_rust_structs() {
        let words = |ty: &str| -> usize {
            wgsl_members(ty)
                .iter()
                .map(|m| if m == "f32" || m == "u32" { 1 } else { m[3..4].parse::<usize>().unwrap() })
                .sum()
        };
        assert_eq!(4 * words("Material"), std::mem::size_of::<GpuMaterial>());
        assert_eq!(4 * words("Light"), std::mem::size_of::<GpuLight>());
        assert_eq!(4 * words("Sphere"), std::mem::size_of::<GpuSphere>());
        assert_eq!(4 * words("Quad"), std::mem::size_of::<GpuQuad>());
        assert_eq!(4 * words("TriShading"), std::mem::size_of::<GpuTriShading>());
        assert_eq!(4 * words("ShadingVertex"), std::mem::size_of::<GpuShadingVertex>());
        assert_eq!(wgsl_members("Material")[1], "u32");
    }
}
