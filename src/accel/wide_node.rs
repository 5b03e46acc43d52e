//! One node of the 8-wide compressed BVH as the GPU reads it (WGSL `WideNode` in `shaders/bvh_wide.wgsl`), and
//! its decoding on the CPU (for tests, statistics and the baked root). The layout is described in
//! [`crate::accel::wide_bvh`], which builds these nodes.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::accel::aabb::Aabb;
use crate::accel::quantise::decode_frame;

/// One 8-wide node (WGSL `WideNode`, same field names); see the module docs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuWideNode {
    pub head: [u32; 4],
    pub links: [u32; 4],
    pub q_lo_xy: [u32; 4],
    pub q_lo_z_hi_x: [u32; 4],
    pub q_hi_yz: [u32; 4],
}

/// Children per node.
pub const WIDTH: usize = 8;
/// Primitive hit bits per node (bits 0–23 of the traversal's hit mask).
pub const MAX_NODE_PRIMS: u32 = 24;
/// A decoded child of a wide node (for tests and statistics).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WideChild {
    Empty,
    /// An interior node: its index in the node list.
    Interior(u32),
    /// A leaf over `prim_refs[first..first + count]`.
    Leaf {
        first: u32,
        count: u32,
    },
}

impl GpuWideNode {
    /// The origin `p` and the per-axis scale `s`.
    pub fn frame(&self) -> (Vec3, Vec3) {
        decode_frame(&self.head)
    }

    fn byte(words: &[u32], i: usize) -> u32 {
        (words[i / 4] >> (8 * (i % 4))) & 0xff
    }

    /// The quantised box of slot `i`, decoded in f32 as the shader does.
    pub fn child_box(&self, i: usize) -> Aabb {
        let (p, s) = self.frame();
        let b = |words: &[u32], j: usize| Self::byte(words, j) as f32;
        let lo = Vec3::new(b(&self.q_lo_xy, i), b(&self.q_lo_xy, 8 + i), b(&self.q_lo_z_hi_x, i));
        let hi = Vec3::new(b(&self.q_lo_z_hi_x, 8 + i), b(&self.q_hi_yz, i), b(&self.q_hi_yz, 8 + i));
        Aabb { min: p + s * lo, max: p + s * hi }
    }

    /// Slot `i`'s meta byte.
    pub fn meta(&self, i: usize) -> u32 {
        Self::byte(&self.links[2..], i)
    }

    /// What slot `i` holds.
    pub fn child(&self, i: usize) -> WideChild {
        let m = self.meta(i);
        let imask = self.head[3] >> 24;
        if m == 0 {
            WideChild::Empty
        } else if m >> 5 == 0 {
            WideChild::Interior(self.links[0] + (imask & ((1 << i) - 1)).count_ones())
        } else {
            WideChild::Leaf { first: self.links[1] + (m & 31), count: m >> 5 }
        }
    }
}
