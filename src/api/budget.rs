//! When a render stops (a sample count or a time) and what it did.

use std::time::Duration;

/// When to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// This many samples per pixel.
    Samples(u32),
    /// Render for this long (pipelines already built), at least one sample per pixel.
    Time(Duration),
}

/// What a render did.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Samples per pixel accumulated in every pixel by this run.
    pub spp: u32,
    /// Film rows that hold one sample more (a time budget's last, partial pass).
    pub extra_rows: u32,
    /// Seconds spent rendering (submissions and waits).
    pub seconds: f64,
    /// Rays traced by this run.
    pub rays: u64,
    /// Non-finite samples counted on the device (a resumed render's include the saved ones).
    pub nonfinite: u64,
    /// Whether the render stopped early because an observer asked it to (Ctrl-C, a notebook's interrupt).
    pub interrupted: bool,
}
