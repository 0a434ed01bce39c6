//! Meshes and listed lights into the world: shared meshes stored once and instanced, the
//! rest flattened into world space with their emissive triangles made lights; quad lights,
//! from a mesh or a list, are one light and the two triangles rays hit.

use super::validate::placeable;
use crate::error::{Error, Result};
use crate::geometry::{Attributes, GeometryBuilder, NO_LIGHT, radial_tangents};
use crate::light::{AreaEmission, Light, QuadLight, TriangleLight};
use crate::limits::{MAX_COORDINATE, MAX_POWER};
use crate::material::{Image, Material};
use crate::math::{Mat3, Mat4, Rgb, Vec3A};
use crate::scene::SceneStats;
use crate::scene::description::{MeshDesc, SceneDescription};

/// One placement of a mesh: its transform and the instance's name (for messages).
pub(super) type Placement<'a> = (Mat4, &'a str);

/// What placing meshes and lights builds up.
pub(super) struct Placer<'a> {
    pub desc: &'a SceneDescription,
    pub images: &'a [Image],
    pub geo: GeometryBuilder,
    pub lights: Vec<Light>,
    /// The description's materials, and the black one listed quad lights show.
    pub materials: Vec<Material>,
    emitter_material: Option<u32>,
    pub stats: SceneStats,
    pub degenerate_emitters: usize,
}

impl<'a> Placer<'a> {
    pub fn new(desc: &'a SceneDescription, images: &'a [Image]) -> Self {
        Self {
            desc,
            images,
            geo: GeometryBuilder::new(),
            lights: Vec::new(),
            materials: desc.materials.clone(),
            emitter_material: None,
            stats: SceneStats::default(),
            degenerate_emitters: 0,
        }
    }

    /// Places every mesh as `placements` says (shared, or flattened once per placement).
    pub fn place_meshes(&mut self, placements: &[(Vec<Placement>, bool)]) -> Result<()> {
        for (mesh, (p, shared)) in self.desc.meshes.iter().zip(placements) {
            if *shared {
                self.place_shared(mesh, p)?;
            } else {
                for &placement in p {
                    self.place_flat(mesh, placement)?;
                }
            }
        }
        Ok(())
    }

    /// Adds the lights the description lists, checked; a quad light also shows as two
    /// triangles with a black material, so camera and BSDF rays can hit it.
    pub fn place_lights(&mut self) -> Result<()> {
        for (i, l) in self.desc.lights.iter().enumerate() {
            let light = super::lights::light(&self.desc.source, i, l)?;
            if let Light::Quad(q) = &light {
                let material = self.emitter_material();
                let id = self.lights.len() as u32;
                self.push_quad(id, q.triangles().map(|t| (t, [0, 1, 2])), None, material, false);
            }
            self.lights.push(light);
        }
        Ok(())
    }

    fn emitter_material(&mut self) -> u32 {
        *self.emitter_material.get_or_insert_with(|| {
            self.materials.push(Material { name: "<light>".into(), ..Material::diffuse("", Rgb::ZERO) });
            (self.materials.len() - 1) as u32
        })
    }

    /// The two triangles of quad light `light` (corners, and the vertex indices `attr` is
    /// addressed by).
    fn push_quad(
        &mut self,
        light: u32,
        triangles: [([Vec3A; 3], [u32; 3]); 2],
        attr: Option<Attributes>,
        material: u32,
        masked: bool,
    ) {
        for (corners, indices) in triangles {
            self.geo.push_triangle(corners, indices, attr, material, light, masked);
        }
        self.stats.emissive_triangles += 2;
    }

    fn err(&self, mesh: &MeshDesc, instance: &str, message: String) -> Error {
        Error::scene(&self.desc.source, format!("instance '{instance}' of mesh '{}'", mesh.name), message)
    }

    /// An error when a placed vertex lands outside what myriad can hold.
    fn check_placed(&self, mesh: &MeshDesc, instance: &str, p: Vec3A) -> Result<()> {
        if placeable(p) {
            return Ok(());
        }
        Err(self.err(
            mesh,
            instance,
            format!(
                "puts a vertex at {p}, which is not finite or lies beyond ±{MAX_COORDINATE} m; scale the scene down"
            ),
        ))
    }

    /// Pushes a mesh's vertex attributes (object space, or transformed by `m`), with the
    /// radial tangents its material asks for.
    fn attributes(&mut self, mesh: &MeshDesc, m: Option<Mat4>) -> Option<Attributes> {
        let radial = self.desc.materials[mesh.material as usize].needs_radial_tangents();
        if mesh.normals.is_none() && mesh.uvs.is_none() && !radial {
            return None;
        }
        let nm = m.map(|m| Mat3::from_mat4(m).inverse().transpose());
        let normals: Option<Vec<Vec3A>> = mesh.normals.as_ref().map(|ns| match nm {
            Some(nm) => ns.iter().map(|&n| (nm * n).normalize_or_zero()).collect(),
            None => ns.clone(),
        });
        // Transformed as normals are, as Cycles' tangent node does.
        let tangents = radial.then(|| {
            let ts = radial_tangents(&mesh.positions);
            match nm {
                Some(nm) => ts.into_iter().map(|t| nm * t).collect(),
                None => ts,
            }
        });
        let count = mesh.positions.len();
        let base =
            self.geo.push_vertices_with_tangents(normals.as_deref(), mesh.uvs.as_deref(), tangents.as_deref(), count);
        Some(Attributes { base, smooth: mesh.normals.is_some(), has_uv: mesh.uvs.is_some() })
    }

    /// Adds a shared mesh once, in object space, and each of its placements.
    fn place_shared(&mut self, mesh: &MeshDesc, placements: &[Placement]) -> Result<()> {
        // Each placement's box corners bound where its vertices land.
        let (lo, hi) = crate::math::point_bounds(mesh.positions.iter().copied());
        for &(m, name) in placements {
            for k in 0..8 {
                let corner = Vec3A::select(glam::BVec3A::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), hi, lo);
                self.check_placed(mesh, name, m.transform_point3a(corner))?;
            }
        }
        let masked = self.desc.materials[mesh.material as usize].has_alpha();
        let attr = self.attributes(mesh, None);
        let block = self.geo.add_shared_mesh(&mesh.positions, &mesh.triangles, attr, mesh.material, masked);
        for &(m, _) in placements {
            self.geo.add_instance(block, m);
        }
        self.stats.instances += placements.len();
        Ok(())
    }

    /// Adds every triangle of one placement to the flattened block, creating lights for
    /// emissive ones.
    fn place_flat(&mut self, mesh: &MeshDesc, (m, name): Placement) -> Result<()> {
        let material = &self.desc.materials[mesh.material as usize];
        // A mirroring transform reverses the winding; swap two corners to keep the front
        // side (glTF: the front of a negative-determinant node is its clockwise side).
        let flip = Mat3::from_mat4(m).determinant() < 0.0;
        let positions: Vec<Vec3A> = mesh.positions.iter().map(|&p| m.transform_point3a(p)).collect();
        if let Some(&p) = positions.iter().find(|p| !placeable(**p)) {
            return self.check_placed(mesh, name, p);
        }
        let attr = self.attributes(mesh, Some(m));
        let emission = AreaEmission { radiance: material.emission, two_sided: material.double_sided };
        let (emissive, masked) = (material.is_emissive(), material.has_alpha());
        let corners = |t: [u32; 3]| if flip { [t[0], t[2], t[1]] } else { t };
        self.stats.instances += 1;
        // Emissive triangles pair into quad lights where consecutive ones make a
        // parallelogram of one emission (a textured one varies over each triangle).
        let pairs = emissive && material.emission_texture.is_none();
        let place = |t: [u32; 3]| corners(t).map(|i| positions[i as usize]);
        let mut rest = &mesh.triangles[..];
        while let Some((&t, tail)) = rest.split_first() {
            rest = tail;
            if let Some(&u) = tail.first().filter(|_| pairs)
                && let Some(q) = QuadLight::from_triangles(place(t), place(u), emission)
            {
                let id = self.add_light(mesh, name, Light::Quad(q))?;
                self.push_quad(id, [t, u].map(|t| (place(t), corners(t))), attr, mesh.material, masked);
                rest = &tail[1..];
                continue;
            }
            let mut id = NO_LIGHT;
            if emissive {
                let light =
                    TriangleLight::new(place(t), emission).map(|l| match (&material.emission_texture, &mesh.uvs) {
                        (Some(tex), Some(uvs)) => {
                            l.with_texture(*tex, corners(t).map(|i| uvs[i as usize]), self.images)
                        }
                        _ => l,
                    });
                match light {
                    Some(l) => {
                        id = self.add_light(mesh, name, Light::Triangle(l))?;
                        self.stats.emissive_triangles += 1;
                    }
                    None => self.degenerate_emitters += 1,
                }
            }
            self.geo.push_triangle(place(t), corners(t), attr, mesh.material, id, masked);
        }
        Ok(())
    }

    /// Adds an emitter of `mesh`; an error when its power is beyond what the samplers'
    /// arithmetic holds.
    fn add_light(&mut self, mesh: &MeshDesc, instance: &str, light: Light) -> Result<u32> {
        let power = light.power(0.0);
        if !(power <= MAX_POWER) {
            let material = &self.desc.materials[mesh.material as usize];
            return Err(self.err(
                mesh,
                instance,
                format!(
                    "emits {power:e} W from one triangle (material '{}', emission {}), beyond myriad's limit of {MAX_POWER:e} W",
                    material.name, material.emission
                ),
            ));
        }
        self.lights.push(light);
        Ok((self.lights.len() - 1) as u32)
    }
}
