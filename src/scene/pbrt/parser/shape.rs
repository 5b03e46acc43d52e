//! pbrt-v4's `Shape` directive onto mislab's builder: cut-out masks, the area light it carries, and each shape
//! kind (triangle and bilinear meshes, PLY files, disks, spheres) with its transform and material.

use super::*;

impl Parser {
    pub(super) fn shape(&mut self, s: ShapeCall) -> Result<(), SceneError> {
        let p = &*s.params;
        let emission = s.area.as_ref().map_or(Vec3::ZERO, |a| a.radiance);
        // Cut-outs: a float texture (its image is the mask) or a constant (0 = the shape is invisible).
        let mut mask = None;
        match p.type_of("alpha") {
            Some("texture") => {
                let name = p.string_of("alpha", &["texture"])?.expect("present");
                match self.textures.get(&name) {
                    Some(MatParam::Texture(t)) => {
                        if t.uv != [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
                            self.b.ignore("uscale/vscale/udelta/vdelta of alpha textures (the mask uses the mesh uv)");
                        }
                        let (file, by) = (t.file.clone(), t.referenced_by.clone());
                        mask = Some(self.b.alpha_mask(&file, &by)?);
                    }
                    Some(_) => self.b.ignore("non-image alpha textures (opaque)"),
                    None => return Err(p.error(format!("\"texture alpha\" \"{name}\": no such texture"))),
                }
            }
            Some(_) if p.float("alpha", 1.0)? < 0.5 => {
                self.b.count("shapes cut out by \"float alpha\" 0", 1);
                return Ok(());
            }
            _ => {}
        }
        let to_world = (self.mirror * s.ctm).as_mat4();
        let flip = s.reverse ^ (Mat3::from_mat4(to_world).determinant() < 0.0);
        let mesh: Option<ObjectMesh> = match s.kind.as_str() {
            "trianglemesh" => Some(shapes::inline_mesh(p, "trianglemesh", false)?),
            "bilinearmesh" => Some(shapes::inline_mesh(p, "bilinearmesh", true)?),
            "plymesh" => {
                if p.has("displacement") || p.has("edgelength") {
                    self.b.ignore("plymesh displacement");
                }
                Some(shapes::ply_mesh(p, &self.dir)?)
            }
            "disk" => {
                if p.float("innerradius", 0.0)? > 0.0 || p.float("phimax", 360.0)? < 360.0 {
                    self.b.ignore("partial disks (rendered whole)");
                }
                Some(shapes::disk(p, s.reverse)?)
            }
            "sphere" => None,
            other => {
                self.b.ignore_at(format!("Shape \"{}\"", clip(other, 40)), at(&p.file, p.line));
                return Ok(());
            }
        };
        let two_sided = s.area.as_ref().is_some_and(|a| a.two_sided);
        let Some(material) = self.b.material(s.material, emission, two_sided)? else {
            self.b.invisible_shapes += 1;
            return Ok(());
        };
        let material = match mask {
            Some(t) if s.kind != "sphere" => self.b.masked_material(material, t),
            Some(_) => {
                self.b.ignore("alpha cut-outs on spheres (rendered opaque)");
                material
            }
            None => material,
        };
        match mesh {
            Some(m) => self.b.add_mesh(m, to_world, flip, material).map_err(|e| p.error(e))?,
            None => {
                let radius = p.float("radius", 1.0)?;
                if !(radius > 0.0) {
                    return Err(p.error(format!("sphere radius {radius} must be > 0")));
                }
                if p.has("zmin") || p.has("zmax") || p.has("phimax") {
                    self.b.ignore("partial spheres (rendered whole)");
                }
                if s.reverse && s.area.is_some() {
                    self.b.ignore("ReverseOrientation on sphere emitters (they emit outwards)");
                }
                self.b.add_sphere(to_world, radius, material).map_err(|e| p.error(e))?;
            }
        }
        self.b.count(&format!("{} shapes", s.kind), 1);
        for u in p.unused() {
            self.b.ignore(format!("Shape \"{}\" parameter {u}", s.kind));
        }
        Ok(())
    }
}
