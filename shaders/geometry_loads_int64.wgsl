// geometry_loads_int64.wgsl — geometry_loads.wgsl for a device with 64-bit integers: `tri_verts` and `wide_nodes`
// are bound as array<vec4<u64>>, so one load brings 32 bytes. lavapipe runs a storage load whose address differs
// between lanes as a loop over the lanes that costs per lane, not per byte (a vec4<u64> costs what a vec4<u32>
// does, docs/platform-notes.md): a triangle takes two loads instead of three, a wide node three instead of five.
// Neither is 32-byte aligned (48 and 80 bytes), so an odd one starts in the upper half of its first element; the
// buffers are padded to whole 32-byte elements (src/render/bindings.rs `READ_32_BYTES_AT_A_TIME`). Words never
// pass through a float register but as the positions' final bitcast (w holds integer records).

/// The four words of two u64s (little-endian: the low word first, as the CPU wrote them).
fn u64_words(p: vec2<u64>) -> vec4<u32> {
    return vec4<u32>(u32(p.x), u32(p.x >> 32u), u32(p.y), u32(p.y >> 32u));
}

/// Vertex k of `tri_verts` as words: one half of a 32-byte element.
fn tri_verts_words(k: u32) -> vec4<u32> {
    let e = tri_verts[k >> 1u];
    return u64_words(select(e.xy, e.zw, (k & 1u) == 1u));
}

/// How many vertices `tri_verts` holds. Where it is followed by further vertex bindings it holds an even number
/// (src/render/gpu_scene.rs `split_vertices`), so the padding never counts.
fn tri_verts_len() -> u32 {
    return 2u * arrayLength(&tri_verts);
}

/// Triangle i's vertices (48 bytes from element 3i/2): an even triangle is one element and the lower half of the
/// next, an odd one the upper half of one and the whole next. Two loads.
fn tri_words(i: u32) -> TriWords {
    let odd = (i & 1u) == 1u;
    let a = (3u * i) >> 1u;
    let l1 = tri_verts[a];
    let l2 = tri_verts[a + 1u];
    return TriWords(u64_words(select(l1.xy, l1.zw, odd)), u64_words(select(l1.zw, l2.xy, odd)),
                    u64_words(select(l2.xy, l2.zw, odd)));
}

/// Wide BVH node i (80 bytes from element 5i/2), the same way: three loads.
fn wide_node(i: u32) -> WideNode {
    let odd = (i & 1u) == 1u;
    let a = (5u * i) >> 1u;
    let l1 = wide_nodes[a];
    let l2 = wide_nodes[a + 1u];
    let l3 = wide_nodes[a + 2u];
    return WideNode(u64_words(select(l1.xy, l1.zw, odd)), u64_words(select(l1.zw, l2.xy, odd)),
                    u64_words(select(l2.xy, l2.zw, odd)), u64_words(select(l2.zw, l3.xy, odd)),
                    u64_words(select(l3.xy, l3.zw, odd)));
}

/// How many wide nodes the binding holds (its padding is less than a node).
fn wide_node_count() -> u32 {
    return (2u * arrayLength(&wide_nodes)) / 5u;
}
