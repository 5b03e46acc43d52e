//! Mouse camera control: orbit about a pivot in front of the camera, pan in the image plane, zoom
//! towards the pivot. Pure functions of a `Camera`, so they are tested without a window.

use crate::scene::Camera;
use glam::{Quat, Vec3};

/// The camera plus the distance to the point it orbits about (on its forward axis).
#[derive(Clone, Debug, PartialEq)]
pub struct Orbit {
    /// The camera.
    pub camera: Camera,
    /// Distance from the camera to the pivot along `forward`.
    pub distance: f32,
}

impl Orbit {
    /// Orbits about the point of the forward axis nearest to `centre` (the scene's centre), so the view
    /// does not jump when the first drag starts.
    pub fn new(camera: Camera, centre: Vec3) -> Orbit {
        let f = camera.forward.normalize_or(Vec3::NEG_Z);
        let d = (centre - camera.position).dot(f);
        let distance = if d.is_finite() && d > 1e-3 { d } else { 1.0 };
        Orbit { camera: Camera { forward: f, ..camera }, distance }
    }

    /// The pivot point.
    pub fn pivot(&self) -> Vec3 {
        self.camera.position + self.camera.forward * self.distance
    }

    /// Rotates about the pivot: `yaw` about world +Y (radians, positive = camera moves right),
    /// `pitch` about the camera's right axis, stopping 1° short of the poles.
    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let pivot = self.pivot();
        let up = Vec3::Y;
        let (right, _, f) = self.camera.frame();
        let elevation = f.dot(up).clamp(-1.0, 1.0).asin();
        let limit = 89f32.to_radians();
        let pitch = (elevation - pitch).clamp(-limit, limit) - elevation;
        let q = Quat::from_axis_angle(up, -yaw) * Quat::from_axis_angle(right, -pitch);
        let forward = (q * f).normalize();
        self.camera.forward = forward;
        self.camera.up = up;
        self.camera.position = pivot - forward * self.distance;
    }

    /// Moves camera and pivot in the image plane by a drag of (`dx`, `dy`) pixels on an image
    /// `image_height` pixels tall (the point under the cursor at the pivot's depth follows it).
    pub fn pan(&mut self, dx: f32, dy: f32, image_height: f32) {
        let (right, up, _) = self.camera.frame();
        let world_per_px = 2.0 * self.distance * (0.5 * self.camera.vfov).tan() / image_height.max(1.0);
        self.camera.position += (-dx * right + dy * up) * world_per_px;
    }

    /// Moves towards the pivot: the distance is multiplied by `factor` (< 1 = closer).
    pub fn zoom(&mut self, factor: f32) {
        let pivot = self.pivot();
        self.distance = (self.distance * factor).clamp(1e-3, 1e6);
        self.camera.position = pivot - self.camera.forward * self.distance;
    }
}
