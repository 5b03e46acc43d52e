//! The camera: a pinhole at a position looking along a direction, its vertical field of view, and the part of
//! the film the image shows (a film crop).

use glam::Vec3;

/// A pinhole camera. The film's aspect ratio comes from the render settings (width / height).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Approximate up vector (orthogonalised against `forward` when the frame is built).
    pub up: Vec3,
    /// Vertical field of view, radians (of the whole film, whatever `window` crops).
    pub vfov: f32,
    /// The part of the film the image shows, as fractions of its width and height: `[x0, x1, y0, y1]`, x right and y
    /// down from the top-left corner. [`Camera::FULL_WINDOW`] but for a film crop (pbrt-v4's `cropwindow` and
    /// `pixelbounds`, Mitsuba's `crop_*`): the image is then that rectangle of the full view, at the render's size.
    pub window: [f32; 4],
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            position: Vec3::new(0.0, 0.0, 5.0),
            forward: Vec3::NEG_Z,
            up: Vec3::Y,
            vfov: 45f32.to_radians(),
            window: Camera::FULL_WINDOW,
        }
    }
}

impl Camera {
    /// The whole film.
    pub const FULL_WINDOW: [f32; 4] = [0.0, 1.0, 0.0, 1.0];

    /// A camera at `position` looking at `target`.
    pub fn look_at(position: Vec3, target: Vec3, up: Vec3, vfov_degrees: f32) -> Self {
        Camera {
            position,
            forward: (target - position).normalize(),
            up,
            vfov: vfov_degrees.to_radians(),
            window: Camera::FULL_WINDOW,
        }
    }
    /// The view through a film crop (`window`), for an image of `width`×`height`: the forward vector and
    /// tan(fov/2) the shader's pinhole (`camera_direction` in shaders/integrator.wgsl) takes. It maps the image to
    /// x, y in [-1, 1] scaled by tan(fov/2) (and the aspect) around `forward`; a window of the whole film is the same
    /// map over a part of it: a smaller tan(fov/2), by the window's height, around a forward moved (not normalised,
    /// no longer orthogonal to right and up) to the window's centre. The whole film's aspect follows from the
    /// image's and the window's. Without a crop, `(forward, tan(vfov/2))` bit for bit.
    pub fn cropped_view(&self, forward: Vec3, right: Vec3, up: Vec3, width: u32, height: u32) -> (Vec3, f32) {
        let t = (0.5 * self.vfov).tan();
        if self.window == Camera::FULL_WINDOW {
            return (forward, t);
        }
        let [x0, x1, y0, y1] = self.window;
        let full_aspect = (width as f32 / height as f32) * (y1 - y0) / (x1 - x0);
        let shift_x = (x0 + x1 - 1.0) * t * full_aspect;
        let shift_y = (1.0 - y0 - y1) * t;
        (forward + shift_x * right + shift_y * up, t * (y1 - y0))
    }

    /// Orthonormal (right, up, forward) frame.
    pub fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let f = self.forward.normalize();
        let mut r = f.cross(self.up);
        if r.length_squared() < 1e-12 {
            r = f.any_orthonormal_vector();
        }
        let r = r.normalize();
        (r, r.cross(f), f)
    }
}
