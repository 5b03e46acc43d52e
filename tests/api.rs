//! The embeddable API (`mislab::api`): one loop for every budget, observers that watch and stop, a render in steps
//! equal to one render, and flags named once for every front end.

mod scratch;

use mislab::api::{self, Budget, Job, Lab, Observer, Progress, RenderFlags, SceneHandle};

fn lab() -> Lab {
    Lab::open().expect("no GPU adapter (install Mesa's lavapipe: apt-get install mesa-vulkan-drivers)")
}

fn job(pairs: &[(&str, &str)]) -> Job {
    Job::from_pairs(pairs).expect("flags")
}

const SMALL: [(&str, &str); 3] = [("width", "40"), ("height", "24"), ("seed", "4")];

#[test]
fn flags_parse_like_the_command_line_and_name_what_is_wrong() {
    let f = RenderFlags::from_pairs(&[("spp", "12"), ("light_sampling", "area"), ("part", "1/3")]).unwrap();
    assert_eq!(f.spp, Some(12));
    assert_eq!(f.settings.light_sampling.name(), "area");
    assert_eq!(f.state.part, Some((1, 3)));
    let e = RenderFlags::from_pairs(&[("no_such_flag", "1")]).unwrap_err().to_string();
    assert!(e.contains("--no-such-flag"), "{e}");
    let e = RenderFlags::from_pairs(&[("strategy", "bogus")]).unwrap_err().to_string();
    assert!(e.contains("bogus") && e.contains("mis"), "{e}");
    assert!(matches!(Job::from_pairs(&[("spp", "0")]), Err(api::ApiError::Settings(_))));
    // --part without a state file to write: Python has no output name to derive one from.
    assert!(matches!(Job::from_pairs(&[("spp", "4"), ("part", "0/2")]), Err(api::ApiError::State(_))));
    let every = RenderFlags::describe();
    let strategy = every.iter().find(|f| f.name == "strategy").unwrap();
    assert!(strategy.choices.contains(&"mis".to_string()) && strategy.default.as_deref() == Some("mis"));
}

#[test]
fn a_missing_scene_is_not_found_and_a_bad_one_a_scene_error() {
    let e = SceneHandle::named("no-such-dir/none.gltf").err().unwrap();
    assert!(matches!(e, api::ApiError::NotFound(_)), "{e}");
    let dir = scratch::Scratch::new("api", "bad-scene");
    let bad = dir.join("bad.pbrt");
    std::fs::write(&bad, "WorldBegin\nFrobnicate 1\n").unwrap();
    let e = SceneHandle::named(bad.to_str().unwrap()).err().unwrap();
    assert!(matches!(e, api::ApiError::Scene(_)) && e.to_string().contains("bad.pbrt: line 2"), "{e}");
}

/// Counts progress calls and stops after `stop_after` of them.
struct StopAfter {
    calls: u32,
    stop_after: u32,
    last: Progress,
}

impl Observer for StopAfter {
    fn progress(&mut self, p: &Progress) {
        self.calls += 1;
        self.last = *p;
    }
    fn stop_requested(&mut self) -> bool {
        self.calls >= self.stop_after
    }
}

#[test]
fn an_observer_sees_progress_and_stops_the_render_with_what_it_has() {
    let lab = lab();
    let scene = SceneHandle::named("veach-mis").unwrap();
    let mut j = job(&[("time", "600"), SMALL[0], SMALL[1], SMALL[2]]);
    j.submit_seconds = 0.01;
    let mut watch = StopAfter { calls: 0, stop_after: 3, last: Progress::default() };
    let img = api::render(&lab, &scene, &mut j, &mut watch).unwrap();
    assert!(img.stats.interrupted && watch.calls == 3);
    assert_eq!(img.spp(), watch.last.spp);
    assert!(img.spp() >= 3 && img.film.count.iter().all(|&c| c == img.spp()));
    assert!(img.stats.rays > 0 && img.stats.seconds > 0.0);
}

#[test]
fn a_render_in_steps_is_the_render_at_once_bit_for_bit_and_pipelines_are_kept() {
    let lab = lab();
    let scene = SceneHandle::named("veach-mis").unwrap();
    let flags = [("spp", "6"), ("mode", "path"), ("sampler", "sobol"), SMALL[0], SMALL[1], SMALL[2]];
    let whole = api::render(&lab, &scene, &mut job(&flags), &mut api::Unobserved).unwrap();
    let compiled = lab.pipelines_compiled();
    let mut j = job(&flags);
    let mut r = api::Render::begin(&lab, &scene, &mut j, &mut api::Unobserved).unwrap();
    for n in [1, 2, 3] {
        r.advance(&lab, api::Plan::of(Budget::Samples(n)), &mut api::Unobserved).unwrap();
    }
    let steps = r.image(&lab).unwrap();
    assert_eq!(steps.spp(), 6);
    assert_eq!(lab.pipelines_compiled(), compiled, "the same settings compile nothing new");
    let bits = |i: &api::Image| i.mean().iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&whole), bits(&steps));
}

/// The Bitterli scenes beside the crate (`../shared`).
fn bitterli(rel: &str) -> String {
    format!("{}/../shared/testdata/scenes/bitterli/{rel}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn a_scene_files_render_settings_are_the_defaults_and_flags_override_them() {
    use mislab::render::settings::{Mode, PixelFilter, SamplerKind};
    // pbrt-v4: `Integrator "volpath" "integer maxdepth" [65]`, `Sampler "sobol" "integer pixelsamples" [1]`, Film.
    let stairs = SceneHandle::named(&bitterli("staircase2/pbrt-v4/scene-v4.pbrt")).unwrap();
    let f = &stairs.scene().file_settings;
    assert_eq!(f.max_depth.as_ref().map(|m| m.0), Some(65));
    assert!(f.max_depth.as_ref().unwrap().1.contains("scene-v4.pbrt: line 1"), "{f:?}");
    assert_eq!(f.spp.as_ref().map(|s| s.0), Some(1));
    let mut j = Job::from_pairs::<&str, &str>(&[]).unwrap();
    let notes = j.resolve(&stairs);
    assert_eq!((j.settings.mode, j.settings.max_depth, j.budget), (Mode::Path, 65, Budget::Samples(1)));
    assert_eq!([j.settings.width, j.settings.height], stairs.film_size().unwrap());
    assert_eq!(notes.len(), 5, "{notes:?}");
    // `Sampler "sobol"`.
    assert_eq!(j.settings.sampler, SamplerKind::Sobol);
    // `PixelFilter "triangle" "float xradius" [1] "float yradius" [1]`.
    assert_eq!((j.settings.filter, j.settings.filter_radius()), (PixelFilter::Triangle, 1.0));
    assert!(
        notes.iter().any(|n| n.contains("--filter triangle --filter-radius 1 ") && n.contains("line 6")),
        "{notes:?}"
    );
    assert!(notes.iter().any(|n| n.contains("--max-depth 65") && n.contains("Integrator \"volpath\"")), "{notes:?}");
    // Flags given win, each on its own.
    let mut j = Job::from_pairs(&[("max_depth", "17"), ("spp", "8"), ("width", "64")]).unwrap();
    j.resolve(&stairs);
    assert_eq!((j.settings.mode, j.settings.max_depth, j.budget), (Mode::Path, 17, Budget::Samples(8)));
    assert_eq!(j.settings.width, 64);
    let mut j = Job::from_pairs(&[("sampler", "independent")]).unwrap();
    j.resolve(&stairs);
    assert_eq!(j.settings.sampler, SamplerKind::Independent, "--sampler given wins");
    let mut j = Job::from_pairs(&[("filter", "gaussian")]).unwrap();
    j.resolve(&stairs);
    assert_eq!(
        (j.settings.filter, j.settings.filter_radius()),
        (PixelFilter::Gaussian, 1.5),
        "a filter given, its defaults"
    );
    let mut j = Job::from_pairs(&[("mode", "direct")]).unwrap();
    j.resolve(&stairs);
    assert_eq!(j.settings.mode, Mode::Direct);
    // The same flag at its default value is still a flag given: --mode direct is what was asked.
    // Mitsuba 3: `<integrator type="path">` with max_depth 65 (vertices: 64 bounces), `<sampler>` sample_count 64.
    let cornell = SceneHandle::named(&bitterli("cornell-box/mitsuba3/scene_v3.xml")).unwrap();
    let mut j = Job::from_pairs::<&str, &str>(&[]).unwrap();
    j.resolve(&cornell);
    assert_eq!((j.settings.mode, j.settings.max_depth, j.budget), (Mode::Path, 64, Budget::Samples(64)));
    assert_eq!(j.settings.sampler, SamplerKind::Independent, "<sampler type=\"independent\">");
    // Its film's `<rfilter type="tent"/>`: Mitsuba's tent, radius 1 by default.
    assert_eq!((j.settings.filter, j.settings.filter_radius()), (PixelFilter::Triangle, 1.0));
    // A built-in scene states nothing: the flags' defaults stand.
    let veach = SceneHandle::named("veach-mis").unwrap();
    let mut j = Job::from_pairs::<&str, &str>(&[]).unwrap();
    assert!(j.resolve(&veach).is_empty());
    assert_eq!((j.settings.mode, j.budget), (Mode::Direct, Budget::Samples(api::DEFAULT_SPP)));
    // A file's sampler is taken only where it can render the sample count: stratified has a maximum (2^20).
    let dir = scratch::Scratch::new("api", "file-sampler");
    let scene_with = |sampler: &str| {
        let path = dir.join("s.pbrt");
        let text = format!("{sampler}\nWorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\nShape \"sphere\"\n");
        std::fs::write(&path, text).unwrap();
        SceneHandle::named(path.to_str().unwrap()).unwrap()
    };
    let mut j = Job::from_pairs::<&str, &str>(&[]).unwrap();
    j.resolve(&scene_with(r#"Sampler "halton" "integer pixelsamples" [ 8 ]"#));
    assert_eq!((j.settings.sampler, j.budget), (SamplerKind::Halton, Budget::Samples(8)));
    let mut j = Job::from_pairs::<&str, &str>(&[]).unwrap();
    j.resolve(&scene_with(r#"Sampler "stratified" "integer xsamples" [ 2048 ] "integer ysamples" [ 2048 ]"#));
    assert_eq!((j.settings.sampler, j.budget), (SamplerKind::Independent, Budget::Samples(1 << 22)));
    std::fs::remove_dir_all(&dir).unwrap();
}
