//! What a front end sees of a render while it runs, and how it stops one: a progress bar, Ctrl-C, a notebook's
//! interrupt button and a live display are all observers.

/// Where a render stands after a submission.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Progress {
    /// Samples per pixel rendered by this run so far.
    pub spp: u32,
    /// The next sample index (the absolute position in a resumed or split render's sample range).
    pub sample_index: u32,
    /// Seconds since this run's first sample began.
    pub seconds: f64,
    /// Rays traced by this run so far.
    pub rays: u64,
    /// Non-finite samples counted on the device so far (kept out of the image).
    pub nonfinite: u64,
}

/// Where a render's start-up went (`Observer::started`), in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Startup {
    /// From the render being asked for to its first sample: the parts below and the small steps between them.
    pub seconds: f64,
    /// The scene's buffers on the device (the first render of a scene on a lab), the render's own buffers, and
    /// the sky probe of `--env-sampling auto`.
    pub upload: f64,
    /// The pipeline: its WGSL specialised and pruned, translated by naga and created — or found in the lab or in
    /// the pipeline store.
    pub pipeline: f64,
    /// The first dispatch, which does no sampling: a driver that compiles at first use (lavapipe) compiles the
    /// kernel here; elsewhere it is a few milliseconds.
    pub first_dispatch: f64,
}

/// Watches a render; may stop it. Every method is called on the thread that renders.
pub trait Observer {
    /// A line for the user (`note: …` or `warning: …`): by default written to stderr.
    fn note(&mut self, line: &str) {
        eprintln!("{line}");
    }
    /// Start-up is over (scene uploaded, pipeline compiled), and where its time went.
    fn started(&mut self, _startup: &Startup) {}
    /// After every submission.
    fn progress(&mut self, _progress: &Progress) {}
    /// Before every submission: true stops the render, which returns what it has (`interrupted`).
    fn stop_requested(&mut self) -> bool {
        false
    }
}

/// An observer that watches nothing and never stops a render.
pub struct Unobserved;

impl Observer for Unobserved {}

/// An observer made of a progress callback and a stop flag (Ctrl-C handlers set such flags).
pub struct Callbacks<'a, P: FnMut(&Progress)> {
    /// Called after every submission.
    pub progress: P,
    /// Stops the render once set.
    pub stop: &'a std::sync::atomic::AtomicBool,
}

impl<P: FnMut(&Progress)> Observer for Callbacks<'_, P> {
    fn progress(&mut self, progress: &Progress) {
        (self.progress)(progress)
    }
    fn stop_requested(&mut self) -> bool {
        self.stop.load(std::sync::atomic::Ordering::SeqCst)
    }
}
