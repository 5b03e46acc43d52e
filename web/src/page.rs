//! The page around the canvas: its address's query, the status line under the canvas, and the map of the panel's
//! controls (where each is on the canvas) that a test clicks as a user would.

/// Writes a line the page shows under the canvas (and a test reads): `#status`.
pub fn report(line: &str) {
    set_text("status", line);
}

/// Publishes where the panel's controls are: one `name x y` line each (centres, CSS pixels from the canvas's
/// top left), in the hidden `#ui-map`.
pub fn publish_controls(controls: &[(String, eframe::egui::Rect)]) {
    let lines: Vec<String> =
        controls.iter().map(|(name, r)| format!("{name} {:.0} {:.0}", r.center().x, r.center().y)).collect();
    set_text("ui-map", &lines.join("\n"));
}

/// A message on the browser's console.
#[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
pub fn log(line: &str) {
    #[cfg(target_arch = "wasm32")]
    web_sys::console::log_1(&line.into());
    #[cfg(not(target_arch = "wasm32"))]
    eprintln!("{line}");
}

fn set_text(id: &str, text: &str) {
    #[cfg(target_arch = "wasm32")]
    if let Some(e) = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id(id)) {
        if e.text_content().as_deref() != Some(text) {
            e.set_text_content(Some(text));
        }
    }
    #[cfg(not(target_arch = "wasm32"))]
    let _ = (id, text);
}

/// The page address's query as (key, value) pairs.
pub fn query() -> Vec<(String, String)> {
    #[cfg(target_arch = "wasm32")]
    let search = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
    #[cfg(not(target_arch = "wasm32"))]
    let search = String::new();
    search
        .trim_start_matches('?')
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// Seconds since some fixed moment (the page's clock).
pub fn now_s() -> f64 {
    web_time::Instant::now().duration_since(*START.get_or_init(web_time::Instant::now)).as_secs_f64()
}

static START: std::sync::OnceLock<web_time::Instant> = std::sync::OnceLock::new();
