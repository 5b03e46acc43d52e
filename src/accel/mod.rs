//! Acceleration structures built on the CPU for the device: the BVH over primitives (binary, and its 8-wide
//! compressed collapse), the convex solids of tiny scenes, the light tree over emitters and the convex lamps it
//! treats as one light each.

pub mod aabb;
pub mod bvh;
pub mod convex_lamps;
pub mod convex_solids;
pub mod isolated_emitters;
pub mod light_tree;
pub mod mesh_components;
pub mod presplit;
pub mod quantise;
pub mod wide_bvh;
pub mod wide_node;
