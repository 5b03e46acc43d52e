//! Files in and out of the page: what the user drops on it or opens from it arrives here (read by the browser
//! without blocking, then taken by the app at its next frame), and an image leaves as a download.
//!
//! A batch holding a scene file (.gltf .glb .toml .pbrt .xml) starts a new set of files; a batch without one adds
//! to the set in use (the textures a scene said it was missing) and the scene loads again. A lone `.exr` of the
//! film's size dropped on a loaded scene is the reference the relmse view compares with.

use mislab::io::memory_files::MemoryFiles;
use std::cell::RefCell;
use std::rc::Rc;

/// Extensions of the files that are scenes (the rest are what scenes reference).
const SCENE_EXTENSIONS: &[&str] = &["gltf", "glb", "toml", "pbrt", "xml"];

/// A file that arrived: its name (no folders; a browser does not give them) and bytes.
pub struct Arrived {
    pub name: String,
    pub bytes: Vec<u8>,
}

/// Where arriving files wait for the app's next frame.
#[derive(Clone, Default)]
pub struct Inbox {
    batches: Rc<RefCell<Vec<Vec<Arrived>>>>,
    reading: Rc<RefCell<usize>>,
}

impl Inbox {
    /// The batches that arrived since the last call.
    pub fn take(&self) -> Vec<Vec<Arrived>> {
        std::mem::take(&mut *self.batches.borrow_mut())
    }

    /// Whether files are still being read.
    pub fn reading(&self) -> bool {
        *self.reading.borrow() > 0
    }

    /// Files egui saw dropped on the canvas this frame: read them (asynchronously) into one batch.
    pub fn accept_dropped(&self, dropped: Vec<eframe::egui::DroppedFileHandle>) {
        if dropped.is_empty() {
            return;
        }
        #[cfg(target_arch = "wasm32")]
        {
            let (batches, reading) = (self.batches.clone(), self.reading.clone());
            *reading.borrow_mut() += 1;
            wasm_bindgen_futures::spawn_local(async move {
                let mut batch = Vec::new();
                for f in &dropped {
                    let name = f.path().display().to_string();
                    match f.bytes_async().await {
                        Ok(bytes) => batch.push(Arrived { name, bytes }),
                        Err(e) => super::page::log(&format!("{name}: could not be read ({e})")),
                    }
                }
                batches.borrow_mut().push(batch);
                *reading.borrow_mut() -= 1;
            });
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            let batch = dropped
                .iter()
                .filter_map(|f| {
                    Some(Arrived { name: f.path().display().to_string(), bytes: std::fs::read(f.path()).ok()? })
                })
                .collect();
            self.batches.borrow_mut().push(batch);
        }
    }

    /// Opens the browser's file chooser (several files may be chosen); what is chosen arrives as one batch.
    pub fn choose_files(&self) {
        #[cfg(target_arch = "wasm32")]
        {
            use wasm_bindgen::prelude::*;
            use wasm_bindgen::JsCast;
            let Some(document) = web_sys::window().and_then(|w| w.document()) else { return };
            let Ok(input) = document.create_element("input") else { return };
            let Ok(input) = input.dyn_into::<web_sys::HtmlInputElement>() else { return };
            input.set_type("file");
            input.set_multiple(true);
            let (batches, reading) = (self.batches.clone(), self.reading.clone());
            let chosen = input.clone();
            let on_change = Closure::<dyn FnMut()>::new(move || {
                let Some(list) = chosen.files() else { return };
                let files: Vec<web_sys::File> = (0..list.length()).filter_map(|i| list.get(i)).collect();
                let (batches, reading) = (batches.clone(), reading.clone());
                *reading.borrow_mut() += 1;
                wasm_bindgen_futures::spawn_local(async move {
                    let mut batch = Vec::new();
                    for f in files {
                        match wasm_bindgen_futures::JsFuture::from(f.array_buffer()).await {
                            Ok(buffer) => {
                                batch.push(Arrived { name: f.name(), bytes: js_sys::Uint8Array::new(&buffer).to_vec() })
                            }
                            Err(e) => super::page::log(&format!("{}: could not be read ({e:?})", f.name())),
                        }
                    }
                    batches.borrow_mut().push(batch);
                    *reading.borrow_mut() -= 1;
                });
            });
            input.set_onchange(Some(on_change.as_ref().unchecked_ref()));
            on_change.forget();
            input.click();
        }
    }
}

/// The files a page has been given, and which of them is the scene.
#[derive(Default)]
pub struct FileSet {
    pub files: MemoryFiles,
    /// Scene files among them (the main file is chosen from these).
    pub scenes: Vec<String>,
}

/// What a batch of arrived files is for.
pub enum BatchUse {
    /// A new set with scene files in it, the likely main file first.
    NewScene(FileSet),
    /// More files for the set in use.
    More(Vec<Arrived>),
    /// A lone EXR: a reference image (if it is the film's size).
    Reference(Arrived),
}

/// Sorts a batch: a new scene, files for the scene in use, or a reference.
pub fn classify(batch: Vec<Arrived>) -> BatchUse {
    let ext = |n: &str| n.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase()).unwrap_or_default();
    let scenes: Vec<&Arrived> = batch.iter().filter(|a| SCENE_EXTENSIONS.contains(&ext(&a.name).as_str())).collect();
    if scenes.is_empty() {
        if batch.len() == 1 && ext(&batch[0].name) == "exr" {
            return BatchUse::Reference(batch.into_iter().next().unwrap());
        }
        return BatchUse::More(batch);
    }
    // The main file is one no other scene file names (Mitsuba fragments and pbrt includes are named by it).
    let names: Vec<String> = scenes.iter().map(|a| a.name.clone()).collect();
    let named_by_another = |name: &str| {
        scenes.iter().any(|other| other.name != name && String::from_utf8_lossy(&other.bytes).contains(name))
    };
    // Among those, the one that names most of the batch's files (its includes, meshes and textures) comes first.
    let names_of_batch = |a: &Arrived| {
        let text = String::from_utf8_lossy(&a.bytes);
        batch.iter().filter(|b| b.name != a.name && text.contains(b.name.as_str())).count()
    };
    let mut ordered: Vec<String> = names.iter().filter(|n| !named_by_another(n)).cloned().collect();
    let rank = |n: &String| scenes.iter().find(|a| &a.name == n).map_or(0, |a| names_of_batch(a));
    ordered.sort_by(|x, y| rank(y).cmp(&rank(x)).then(x.cmp(y)));
    let mut rest: Vec<String> = names.iter().filter(|n| !ordered.contains(n)).cloned().collect();
    rest.sort();
    ordered.extend(rest);
    let mut set = FileSet { files: MemoryFiles::new(), scenes: ordered };
    for a in batch {
        set.files.insert(&a.name, a.bytes);
    }
    BatchUse::NewScene(set)
}

/// Offers `bytes` to the user as a download named `name`.
pub fn download(name: &str, bytes: &[u8], mime: &str) -> Result<(), String> {
    #[cfg(target_arch = "wasm32")]
    {
        use wasm_bindgen::JsCast;
        let array = js_sys::Uint8Array::from(bytes);
        let parts = js_sys::Array::of1(&array);
        let options = web_sys::BlobPropertyBag::new();
        options.set_type(mime);
        let blob =
            web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &options).map_err(|e| format!("{e:?}"))?;
        let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(|e| format!("{e:?}"))?;
        let document = web_sys::window().and_then(|w| w.document()).ok_or("no document")?;
        let a = document
            .create_element("a")
            .map_err(|e| format!("{e:?}"))?
            .dyn_into::<web_sys::HtmlAnchorElement>()
            .map_err(|_| "not an anchor")?;
        a.set_href(&url);
        a.set_download(name);
        a.click();
        web_sys::Url::revoke_object_url(&url).map_err(|e| format!("{e:?}"))?;
        Ok(())
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        let _ = mime;
        std::fs::write(name, bytes).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arrived(name: &str, text: &str) -> Arrived {
        Arrived { name: name.into(), bytes: text.as_bytes().to_vec() }
    }

    #[test]
    fn the_main_scene_file_is_the_one_no_other_names() {
        let batch = vec![
            arrived("base.xml", "<scene/>"),
            arrived("cbox.xml", "<include filename=\"fragments/base.xml\"/>"),
            arrived("aaa.xml", "<scene/>"),
            arrived("shapes.xml", "<shape filename=\"meshes/floor.obj\"/>"),
            arrived("floor.obj", "v 0 0 0"),
        ];
        match classify(batch) {
            BatchUse::NewScene(set) => {
                assert_eq!(set.scenes, ["cbox.xml", "shapes.xml", "aaa.xml", "base.xml"]);
                assert_eq!(set.files.names(), ["aaa.xml", "base.xml", "cbox.xml", "floor.obj", "shapes.xml"]);
            }
            _ => panic!("a batch with scene files is a new scene"),
        }
        assert!(matches!(classify(vec![arrived("a.png", "x")]), BatchUse::More(_)));
        assert!(matches!(classify(vec![arrived("ref.EXR", "x")]), BatchUse::Reference(_)));
    }
}
