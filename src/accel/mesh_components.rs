//! Connected components of a triangle list: triangles that share a vertex are in one component (union–find over
//! vertex ids). Used by the searches for convex solids and isolated emitters.

use std::collections::HashMap;

/// The components of triangles given by their corners' vertex ids (all below `vertex_count`), as lists of
/// indices into `corners`, each ascending; in no particular order.
pub fn mesh_components(corners: &[[usize; 3]], vertex_count: usize) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..vertex_count).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for c in corners {
        for k in 1..3 {
            let (a, b) = (root(&mut parent, c[0]), root(&mut parent, c[k]));
            parent[a] = b;
        }
    }
    let mut components: HashMap<usize, Vec<usize>> = HashMap::new();
    for (t, c) in corners.iter().enumerate() {
        components.entry(root(&mut parent, c[0])).or_default().push(t);
    }
    components.into_values().collect()
}
