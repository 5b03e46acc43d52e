//! Cameras and lights: perspective cameras placed by nodes, KHR_lights_punctual lights (spot cones
//! sanitised), and the fallback camera that frames the whole scene.

use super::{json, quoted, Loader, Res};
use crate::scene::{Camera, Mesh, PunctualLight};
use glam::{Mat4, Vec3};
use json::extensions::scene::khr_lights_punctual as punctual;
use json::validation::Checked;

impl Loader<'_> {
    /// A perspective camera at the node's world transform; None (with a warning) when it cannot be used.
    pub(super) fn camera(&mut self, index: usize, world: &Mat4) -> Res<Option<Camera>> {
        let count = self.root.cameras.len();
        let camera = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| format!("camera {index} does not exist (the file has {count} cameras)"))?;
        let label = format!("camera {index}{}", quoted(&camera.name));
        let perspective = match (camera.type_, &camera.perspective) {
            (Checked::Valid(json::camera::Type::Perspective), Some(p)) => p,
            (Checked::Valid(json::camera::Type::Orthographic), _) => {
                self.notes.push(format!("{label}: orthographic cameras are not supported; skipped"));
                return Ok(None);
            }
            _ => {
                self.notes.push(format!("{label}: no valid perspective projection; skipped"));
                return Ok(None);
            }
        };
        let vfov = perspective.yfov;
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        if !(vfov > 0.0 && vfov < std::f32::consts::PI) || forward == Vec3::ZERO || up == Vec3::ZERO {
            self.notes.push(format!("{label}: unusable yfov {vfov} or degenerate node transform; skipped"));
            return Ok(None);
        }
        Ok(Some(Camera {
            position: world.transform_point3(Vec3::ZERO),
            forward,
            up,
            vfov,
            window: Camera::FULL_WINDOW,
        }))
    }

    /// Adds a KHR_lights_punctual light placed by a node (lights shine down the node's -Z).
    pub(super) fn light(&mut self, index: usize, world: &Mat4, node: &str) -> Res<()> {
        let lights = self.root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        let lights = lights.map_or(&[][..], |l| &l.lights[..]);
        let light = lights.get(index).ok_or_else(|| {
            format!("{node}: KHR_lights_punctual light {index} does not exist (the file has {})", lights.len())
        })?;
        let label = format!("{node}: light {index}{}", quoted(&light.name));
        let power = Vec3::from(light.color) * light.intensity;
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        if !power.is_finite() || power.min_element() < 0.0 || !position.is_finite() {
            self.notes.push(format!("{label}: negative or non-finite colour × intensity or position; skipped"));
            return Ok(());
        }
        let needs_direction = !matches!(light.type_, Checked::Valid(punctual::Type::Point));
        if needs_direction && direction == Vec3::ZERO {
            self.notes.push(format!("{label}: degenerate node transform gives no direction; skipped"));
            return Ok(());
        }
        let built = match light.type_ {
            Checked::Valid(punctual::Type::Point) => PunctualLight::Point { position, intensity: power },
            Checked::Valid(punctual::Type::Directional) => PunctualLight::Directional { direction, irradiance: power },
            Checked::Valid(punctual::Type::Spot) => {
                let (inner_cone, outer_cone) = self.cone(light.spot.as_ref(), &label);
                PunctualLight::Spot { position, direction, intensity: power, inner_cone, outer_cone }
            }
            Checked::Invalid => {
                self.notes.push(format!("{label}: unknown light type; skipped"));
                return Ok(());
            }
        };
        self.scene.punctual_lights.push(built);
        Ok(())
    }

    /// Spot cone angles (spec defaults 0 and π/4), clamped to 0 ≤ inner < outer ≤ π/2.
    fn cone(&mut self, spot: Option<&punctual::Spot>, label: &str) -> (f32, f32) {
        let quarter = std::f32::consts::FRAC_PI_4;
        let (inner, outer) = spot.map_or((0.0, quarter), |s| (s.inner_cone_angle, s.outer_cone_angle));
        let valid = inner.is_finite()
            && outer.is_finite()
            && inner >= 0.0
            && inner < outer
            && outer <= std::f32::consts::FRAC_PI_2;
        if valid {
            return (inner, outer);
        }
        self.notes.push(format!("{label}: invalid spot cone angles ({inner}, {outer}); using 0 and π/4"));
        (0.0, quarter)
    }
}

/// A camera that sees the whole scene: from +Z towards the bounding-box centre, 45° vertical field of view,
/// far enough that the bounding sphere fits. Only vertices some triangle uses count: an unused one may be anything
/// the file holds (a NaN, which would make the whole camera NaN).
pub(super) fn frame_meshes(meshes: &[Mesh]) -> Camera {
    let mut points =
        meshes.iter().flat_map(|m| m.indices.iter().flatten().filter_map(|&i| m.positions.get(i as usize).copied()));
    let Some(first) = points.next() else { return Camera::default() };
    let (lo, hi) = points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let center = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let vfov = 45f32.to_radians();
    let distance = radius / (vfov * 0.5).sin();
    Camera {
        position: center + Vec3::Z * distance,
        forward: Vec3::NEG_Z,
        up: Vec3::Y,
        vfov,
        window: Camera::FULL_WINDOW,
    }
}
