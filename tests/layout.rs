//! Every struct shared between Rust and WGSL has the same size and member offsets on both sides (naga's
//! own layout of the WGSL), and every WGSL tag constant equals its Rust enum discriminant. No GPU needed.

use mislab::accel::bvh::GpuBvhNode;
use mislab::accel::wide_bvh::GpuWideNode;
use mislab::gpu::types::*;
use mislab::render::settings::*;
use std::mem::{offset_of, size_of};

fn module() -> naga::Module {
    let src = mislab::render::render_source();
    mislab::render::shaders::validate(&src).unwrap_or_else(|e| panic!("render module does not validate:\n{e}"))
}

/// (size, [(member name, offset)]) of a WGSL struct by name.
fn wgsl_layout(m: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    for (_, ty) in m.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                return (*span, members.iter().map(|mm| (mm.name.clone().unwrap_or_default(), mm.offset)).collect());
            }
        }
    }
    panic!("WGSL struct {name} not found (is it used by the render module?)");
}

macro_rules! check {
    ($m:expr, $wgsl:literal, $rust:ty, [$($field:ident),+ $(,)?]) => {{
        let (size, members) = wgsl_layout(&$m, $wgsl);
        let rust: Vec<(&str, usize)> = vec![$((stringify!($field), offset_of!($rust, $field))),+];
        assert_eq!(size as usize, size_of::<$rust>(), "size of {} (WGSL) vs {} (Rust)", $wgsl, stringify!($rust));
        assert_eq!(members.len(), rust.len(), "{}: WGSL has members {:?}", $wgsl, members);
        for ((wn, wo), (rn, ro)) in members.iter().zip(&rust) {
            assert_eq!(wn, rn, "{}: member order/name differs", $wgsl);
            assert_eq!(*wo as usize, *ro, "{}.{}: WGSL offset {} vs Rust {}", $wgsl, wn, wo, ro);
        }
    }};
}

#[test]
fn shared_structs_match() {
    let m = module();
    check!(m, "Sphere", GpuSphere, [center, radius, material, light, _pad0, _pad1]);
    check!(m, "Quad", GpuQuad, [corner, material, edge_u, light, edge_v, _pad0]);
    check!(m, "TriShading", GpuTriShading, [corners, light]);
    check!(m, "ShadingVertex", GpuShadingVertex, [normal, material, uv]);
    check!(
        m,
        "Material",
        GpuMaterial,
        [
            emission,
            bsdf_kind,
            base_tex,
            mr_tex,
            emissive_tex,
            _pad0,
            base_xform0,
            base_xform1,
            mr_xform0,
            mr_xform1,
            em_xform0,
            em_xform1,
            params0,
            params1,
            params2
        ]
    );
    check!(
        m,
        "Light",
        GpuLight,
        [
            position,
            kind,
            direction,
            prim,
            radiance,
            pmf_power,
            cos_inner,
            cos_outer,
            area,
            pmf_uniform,
            tree_trail,
            two_sided,
            shadow_box,
            _pad2
        ]
    );
    check!(m, "LightNode", mislab::accel::light_tree::GpuLightNode, [head, boxes, power_axes, spread_next]);
    check!(m, "AliasEntry", GpuAliasEntry, [prob, alias_index]);
    check!(m, "TextureInfo", GpuTextureInfo, [offset, width, height, wrap_s, wrap_t, srgb, nearest, tex_kind]);
    check!(m, "Accum", GpuAccum, [mean, count, m2, nonfinite]);
    check!(
        m,
        "FrameParams",
        GpuFrameParams,
        [
            width,
            height,
            sample_base,
            samples_per_dispatch,
            seed,
            mode,
            max_depth,
            strategy,
            light_sampling,
            env_sampling,
            light_select,
            heuristic,
            power_beta,
            light_samples,
            bsdf_samples,
            mis_kind,
            sampler,
            num_lights,
            rr_depth,
            env_light,
            cam_origin,
            tan_half_fov,
            cam_right,
            aspect,
            cam_up,
            env_scale,
            cam_forward,
            env_rotation,
            env_constant,
            env_width,
            env_height,
            sampler_spp,
            row_offset,
            row_count,
            offset_scale,
            ris_candidates,
            tile_row_stride,
            first_hit_light_split,
            guide_min,
            guide_train,
            guide_inv_cell,
            guide_slots,
            guide_dims,
            guide_on,
            guide_learner_period,
            lamp_first,
            lamp_count,
            lamps_only,
            occluder_first,
            occluder_count,
            pixel_filter,
            filter_radius,
            filter_sigma,
            filter_norm,
            _pad_filter
        ]
    );
    check!(m, "Hit", GpuHit, [t, prim, b1, b2]);
    check!(m, "BvhNode", GpuBvhNode, [lmin, l_first, lmax, l_count, rmin, r_first, rmax, r_count]);
    check!(m, "WideNode", GpuWideNode, [head, links, q_lo_xy, q_lo_z_hi_x, q_hi_yz]);
}

/// The value of a WGSL `const NAME: u32`.
fn wgsl_const(m: &naga::Module, name: &str) -> u32 {
    for (_, c) in m.constants.iter() {
        if c.name.as_deref() == Some(name) {
            if let naga::Expression::Literal(naga::Literal::U32(v)) = m.global_expressions[c.init] {
                return v;
            }
            panic!("WGSL constant {name} is not a u32 literal");
        }
    }
    panic!("WGSL constant {name} not found");
}

fn wgsl_name(prefix: &str, text: &str) -> String {
    format!("{prefix}{}", text.to_uppercase().replace('-', "_"))
}

macro_rules! check_enum {
    ($m:expr, $ty:ty) => {
        for v in <$ty>::ALL {
            let name = wgsl_name(<$ty>::WGSL_PREFIX, v.name());
            assert_eq!(wgsl_const(&$m, &name), v.tag(), "{name} differs between WGSL and Rust");
        }
    };
}

#[test]
fn tag_constants_match() {
    let m = module();
    check_enum!(m, Mode);
    check_enum!(m, Strategy);
    check_enum!(m, LightSampling);
    check_enum!(m, EnvSampling);
    check_enum!(m, LightSelect);
    check_enum!(m, Heuristic);
    check_enum!(m, MisKind);
    check_enum!(m, SamplerKind);
    check_enum!(m, PixelFilter);
    for (name, v) in [
        ("PRIM_TRIANGLE", PRIM_TRIANGLE),
        ("PRIM_SPHERE", PRIM_SPHERE),
        ("PRIM_QUAD", PRIM_QUAD),
        ("PRIM_KIND_SHIFT", PRIM_KIND_SHIFT),
        ("PRIM_INDEX_MASK", PRIM_INDEX_MASK),
        ("LIGHT_TRIANGLE", LIGHT_TRIANGLE),
        ("LIGHT_SPHERE", LIGHT_SPHERE),
        ("LIGHT_QUAD", LIGHT_QUAD),
        ("LIGHT_POINT", LIGHT_POINT),
        ("LIGHT_SPOT", LIGHT_SPOT),
        ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
        ("LIGHT_ENVIRONMENT", LIGHT_ENVIRONMENT),
        ("LIGHT_CONVEX_LAMP", LIGHT_CONVEX_LAMP),
        ("LIGHT_LAMP_FACE", LIGHT_LAMP_FACE),
        ("WRAP_REPEAT", WRAP_REPEAT),
        ("WRAP_CLAMP", WRAP_CLAMP),
        ("WRAP_MIRROR", WRAP_MIRROR),
        ("TEX_IMAGE", TEX_IMAGE),
        ("TEX_CHECKERBOARD", TEX_CHECKERBOARD),
        ("TEXEL_HI", TEXEL_HI),
        ("INVALID", INVALID),
        ("NO_NORMAL", mislab::render::shading_data::NO_NORMAL),
        ("LIGHT_LEAF_BIT", mislab::accel::light_tree::LEAF_BIT),
        // The light tree's empty child is the shader's INVALID.
        ("INVALID", mislab::accel::light_tree::EMPTY),
        ("GUIDE_Z_BINS", mislab::render::env_guide::Z_BINS as u32),
        ("GUIDE_PHI_BINS", mislab::render::env_guide::PHI_BINS as u32),
        ("GUIDE_BINS", mislab::render::env_guide::BINS as u32),
        ("GUIDE_LEARN", mislab::render::env_guide::LEARN),
        ("GUIDE_LEARN_ONLY", mislab::render::env_guide::LEARN_ONLY),
        ("GUIDE_COMPLETE", mislab::render::env_guide::COMPLETE),
    ] {
        assert_eq!(wgsl_const(&m, name), v, "{name} differs between WGSL and Rust");
    }
    // The material tags are generated from the registry (render::materials): each once, each its own value.
    let materials = mislab::render::materials::MATERIALS;
    for e in materials {
        assert_eq!(wgsl_const(&m, e.tag_const), e.tag, "{} differs between WGSL and the registry", e.tag_const);
        assert_eq!(materials.iter().filter(|o| o.tag == e.tag).count(), 1, "{}: its tag is not its own", e.name);
    }
}

/// Every binding the composed render module declares is in `bindings::{SCENE, FRAME}` with the same name,
/// address space and access, and its element (array stride, or the uniform struct's size) has the size the Rust
/// side uploads; every table entry is declared. The WGSL is generated from the table, so this checks the
/// generator and the element sizes typed into the table against naga's own layout.
#[test]
fn bindings_match_the_table() {
    use mislab::render::bindings::{self, Access};
    let m = module();
    let mut seen = Vec::new();
    for (_, var) in m.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let b = bindings::all()
            .find(|b| b.group == rb.group && b.binding == rb.binding)
            .unwrap_or_else(|| panic!("WGSL binding ({}, {}) is not in the table", rb.group, rb.binding));
        let name = var.name.clone().unwrap_or_default();
        assert_eq!(name, b.name, "binding ({}, {})", b.group, b.binding);
        let access = match var.space {
            naga::AddressSpace::Uniform => Access::Uniform,
            naga::AddressSpace::Storage { access } if access.contains(naga::StorageAccess::STORE) => Access::ReadWrite,
            naga::AddressSpace::Storage { .. } => Access::Read,
            other => panic!("{name}: unexpected address space {other:?}"),
        };
        assert_eq!(access, b.access, "{name}: access");
        let element = match &m.types[var.ty].inner {
            naga::TypeInner::Array { stride, .. } => *stride,
            inner => inner.size(m.to_ctx()),
        };
        assert_eq!(element as usize, b.element_size, "{name}: WGSL element size {element} vs the table's");
        seen.push((b.group, b.binding));
    }
    for b in bindings::all() {
        assert!(
            seen.contains(&(b.group, b.binding)),
            "{} ({}, {}) is not declared in WGSL",
            b.name,
            b.group,
            b.binding
        );
    }
    assert_eq!(bindings::SCENE.len(), mislab::render::gpu_scene::binding_sizes(&Default::default()).len());
}
