//! The light tree's quality without a GPU: for shading points on the floor of a built-in scene, the relative
//! variance per sample, Σᵢ fᵢ²/pᵢ / F² − 1, of choosing one light by the tree's pmf (`light_tree::pmf`) and by
//! power, where fᵢ is light i's unshadowed irradiance treated as a point source (small emitters). What a change
//! to the build or the importance buys, in seconds: `cargo run --release --example light_tree_variance [SCENE]`.

use glam::Vec3;
use mislab::gpu::types::LIGHT_TRIANGLE;
use mislab::render::scene_data::SceneData;

fn main() {
    let name = std::env::args().nth(1).unwrap_or_else(|| "many-lights".into());
    let scene = mislab::scene::builtin::by_name(&name).unwrap_or_else(|| panic!("no built-in scene {name}"));
    let t0 = std::time::Instant::now();
    let d = SceneData::build(&scene);
    let bounded = d.light_tree.first().map_or(0, |n| n.count() as usize);
    eprintln!(
        "{name}: {bounded} lights in the tree, {} nodes, built in {:.2} s",
        d.light_tree.len(),
        t0.elapsed().as_secs_f64()
    );
    let vert = |t: u32, k: u32| Vec3::from_slice(&d.tri_verts[(3 * t + k) as usize][..3]);
    let lights: Vec<(Vec3, Vec3, f32)> = d.lights[..bounded]
        .iter()
        .map(|l| {
            assert_eq!(l.kind, LIGHT_TRIANGLE, "the example knows triangle lights only");
            let (a, b, c) = (vert(l.prim, 0), vert(l.prim, 1), vert(l.prim, 2));
            // Power ∝ radiance × area: a light's irradiance up to one constant factor, which cancels.
            ((a + b + c) / 3.0, (b - a).cross(c - a).normalize(), l.pmf_power)
        })
        .collect();
    let (mut v_tree, mut v_power, mut count) = (0.0f64, 0.0f64, 0);
    let mut per_point: Vec<(f64, Vec3, f64)> = Vec::new();
    let mut state = 12345u32;
    let mut rnd = || {
        state = state.wrapping_mul(747796405).wrapping_add(2891336453);
        let x = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
        ((x >> 22) ^ x) as f32 / u32::MAX as f32
    };
    let n = Vec3::Y;
    for _ in 0..400 {
        let p = Vec3::new(38.0 * rnd() - 19.0, 0.0, 38.0 * rnd() - 19.0);
        let f: Vec<f64> = lights
            .iter()
            .map(|&(c, nl, le)| {
                let w = c - p;
                let d2 = w.length_squared();
                let w = w / d2.sqrt();
                (le * (-w.dot(nl)).max(0.0) * w.dot(n).max(0.0) / d2) as f64
            })
            .collect();
        let total: f64 = f.iter().sum();
        if total <= 0.0 {
            continue;
        }
        let m2 = |pmf: &dyn Fn(usize) -> f64| -> f64 {
            f.iter().enumerate().filter(|(_, &fi)| fi > 0.0).map(|(i, &fi)| fi * fi / pmf(i)).sum::<f64>()
        };
        let tree = m2(&|i| mislab::accel::light_tree::pmf(&d.light_tree, d.lights[i].tree_trail, p, n) as f64);
        let power = m2(&|i| d.lights[i].pmf_power as f64);
        v_tree += tree / (total * total) - 1.0;
        // The light that contributes most, and the share of its contribution the tree gives it.
        let (k, fk) = f.iter().enumerate().fold((0, 0.0), |b, (i, &fi)| if fi > b.1 { (i, fi) } else { b });
        let pk = mislab::accel::light_tree::pmf(&d.light_tree, d.lights[k].tree_trail, p, n) as f64;
        per_point.push((tree / (total * total) - 1.0, p, pk / (fk / total)));
        v_power += power / (total * total) - 1.0;
        count += 1;
    }
    let (vt, vp) = (v_tree / count as f64, v_power / count as f64);
    per_point.sort_by(|a, b| a.0.total_cmp(&b.0));
    let q = |f: f64| per_point[((per_point.len() - 1) as f64 * f) as usize].0;
    println!("tree per point: median {:.2}, 90% {:.2}, 99% {:.2}, max {:.2}", q(0.5), q(0.9), q(0.99), q(1.0));
    for (v, p, ratio) in per_point.iter().rev().take(5) {
        println!("  {v:.1} at {p}: the brightest light gets {ratio:.3} of its share of F");
    }
    println!(
        "{name}: relative variance per sample over {count} floor points: tree {vt:.3}, power {vp:.3}, power/tree {:.2}",
        vp / vt
    );
}
