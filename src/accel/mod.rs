//! Acceleration structures built on the CPU for the device: the BVH over primitives, the convex solids of tiny
//! scenes, and the light tree over emitters.

pub mod bvh;
pub mod convex_solids;
pub mod light_tree;
