//! The lecture suite: the comparisons the lecture makes, as benchmark groups.

use super::*;

/// The lecture suite's groups at `width`×`height`, ladder `spp`, `seeds` seeds.
pub fn lecture_suite(
    inputs: &SuiteInputs,
    width: u32,
    height: u32,
    spp: &[u32],
    seeds: u32,
    reference_spp: u32,
) -> Vec<BenchGroup> {
    let sky = inputs.sky.clone();
    let base = BenchGroup { width, height, spp: spp.to_vec(), seeds, reference_spp, ..BenchGroup::default() };
    let all_samplers = SamplerKind::ALL.to_vec();
    vec![
        BenchGroup {
            name: "Direction sampling: uniform vs cosine vs BSDF (area-vs-cosine)".into(),
            scene: "area-vs-cosine".into(),
            strategies: vec![Strategy::Uniform, Strategy::Cosine, Strategy::Bsdf],
            ..base.clone()
        },
        BenchGroup {
            name: "Area lights: area vs solid-angle sampling (veach-mis, light sampling)".into(),
            scene: "veach-mis".into(),
            strategies: vec![Strategy::Light],
            light_samplings: vec![LightSampling::Area, LightSampling::SolidAngle],
            ..base.clone()
        },
        BenchGroup {
            name: "Environment: uniform vs importance (sphere under noon_grass, light sampling)".into(),
            scene: "furnace".into(),
            env: Some(sky.clone()),
            strategies: vec![Strategy::Light],
            env_samplings: vec![EnvSampling::Uniform, EnvSampling::Importance],
            ..base.clone()
        },
        BenchGroup {
            // MIS here, as a renderer would: the glossy and mirror-like spheres find the sun through BSDF samples.
            name: "Environment: uniform vs importance (metal-rough spheres under noon_grass, MIS)".into(),
            scene: inputs.spheres.to_string_lossy().into_owned(),
            env: Some(sky.clone()),
            strategies: vec![Strategy::Mis],
            env_samplings: vec![EnvSampling::Uniform, EnvSampling::Importance],
            ..base.clone()
        },
        BenchGroup {
            name:
                "Many lights: uniform vs power vs tree vs RIS vs tree-RIS (veach-mis-triangles: 80,640 emitters, MIS)"
                    .into(),
            scene: "veach-mis-triangles".into(),
            strategies: vec![Strategy::Mis],
            light_selects: LightSelect::ALL.to_vec(),
            reference_light_select: LightSelect::Tree,
            ..base.clone()
        },
        BenchGroup {
            name: "Many lights: uniform vs power vs tree vs RIS vs tree-RIS (many-lights: 4,096 emitters, MIS)".into(),
            scene: "many-lights".into(),
            strategies: vec![Strategy::Mis],
            light_selects: LightSelect::ALL.to_vec(),
            reference_light_select: LightSelect::Tree,
            ..base.clone()
        },
        BenchGroup {
            name: "MIS: balance vs power heuristic (veach-mis)".into(),
            scene: "veach-mis".into(),
            strategies: vec![Strategy::Mis],
            heuristics: vec![Heuristic::Balance, Heuristic::Power],
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (veach-mis, MIS)".into(),
            scene: "veach-mis".into(),
            strategies: vec![Strategy::Mis],
            samplers: all_samplers.clone(),
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (area-vs-cosine, MIS)".into(),
            scene: "area-vs-cosine".into(),
            strategies: vec![Strategy::Mis],
            samplers: all_samplers.clone(),
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (sphere under noon_grass, MIS)".into(),
            scene: "furnace".into(),
            env: Some(sky),
            strategies: vec![Strategy::Mis],
            samplers: all_samplers,
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (cornell-box, path tracing, MIS)".into(),
            scene: "cornell-box".into(),
            mode: Mode::Path,
            strategies: vec![Strategy::Mis],
            samplers: vec![SamplerKind::Independent, SamplerKind::Sobol],
            // Path samples cost several times direct ones: a quarter of the samples still leaves the reference's
            // variance 16× below that of the last point (64 spp) at the default ladder.
            reference_spp: (reference_spp / 4).max(1),
            ..base
        },
    ]
}
