//! Every composed shader module parses and validates with naga (no GPU needed), so a WGSL error is a
//! test failure with a readable message rather than a device error at run time.

#[test]
fn render_module_validates() {
    let src = mislab::render::render_source();
    if let Err(e) = mislab::shaders::validate(&src) {
        panic!("render module:\n{e}");
    }
}

#[test]
fn every_file_is_embedded_and_nonempty() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.ends_with(".wgsl") {
            assert!(
                mislab::shaders::FILES.iter().any(|(n, s)| *n == name && !s.trim().is_empty()),
                "{name} is not embedded in src/shaders.rs"
            );
        }
    }
}
