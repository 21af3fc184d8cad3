//! The CPU twin of the ray-traced shading pass's lights with visibility (SPEC §6): the same
//! triangles the GPU draws, one primary ray per pixel centre through a [`SceneBvh`], and shadow
//! rays that leave from the same point, offset the same way, as `shaders/common/ray_surface.glsl`
//! and `visibility.glsl` compute them (f32 throughout, step for step). Shading is
//! `oracle::light_between`'s (`model::lacquer_brdf` under the punctual lights).
//!
//! Where the GPU and this twin can differ: a shadow ray that grazes an edge of an occluder may
//! hit on one side and miss on the other (two different triangle tests), so tests compare p99.

use glam::Vec3;

use super::bvh::SceneBvh;
use crate::model::{BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::draw::RayTracing;
use crate::raster::self_hits::{own_mask_bits, SelfHits};
use crate::raster::{Camera, Light, Mesh};

/// Far enough for a directional light, as `RAY_FAR` in visibility.glsl.
const RAY_FAR: f32 = 1e30;

/// One object: a world-space mesh and its material.
#[derive(Clone, Copy)]
pub struct TracedObject<'a> {
    pub mesh: &'a Mesh,
    pub brdf: &'a BrdfParams,
    pub fresnel: &'a FresnelTable,
}

/// Where rays leave a surface point: ray_surface.glsl's `RaySurface`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaySurface {
    pub point: Vec3,
    /// Unit, on the side of the shading normal.
    pub geometric_normal: Vec3,
    /// Whether the point is shaded from its triangle's winding side (the geometric normal not
    /// turned): which of the mesh's sides the rays leave.
    pub front: bool,
    /// The object no ray leaving here meets: the surface's own, where its mesh is convex on the
    /// side the rays leave (visibility.glsl's `trace_mask`; [`TracedScene::own`]).
    pub own: Option<u32>,
}

fn vertex(mesh: &Mesh, triangle: u32, k: usize) -> (Vec3, Vec3) {
    let index = mesh.indices[3 * triangle as usize + k] as usize;
    (
        Vec3::from(mesh.positions[index]),
        Vec3::from(mesh.normals[index]).normalize(),
    )
}

/// ray_surface.glsl's `ray_surface`: the point `position` on `triangle` of `mesh` (with unit
/// shading normal `n`) clamped into the triangle and lifted onto the smooth surface of its
/// vertex normals (Hanika's shadow-terminator offset), and the geometric normal.
pub fn ray_surface(mesh: &Mesh, triangle: u32, position: Vec3, n: Vec3) -> RaySurface {
    let [(p0, n0), (p1, n1), (p2, n2)] = [0, 1, 2].map(|k| vertex(mesh, triangle, k));
    let (e1, e2) = (p1 - p0, p2 - p0);
    let cross_e = e1.cross(e2);
    let area2 = cross_e.dot(cross_e);
    if area2.is_nan() || area2 <= 0.0 {
        return RaySurface {
            point: position,
            geometric_normal: n,
            front: true,
            own: None,
        };
    }
    let ng = cross_e * area2.sqrt().recip();
    let front = ng.dot(n) >= 0.0;
    let geometric_normal = if front { ng } else { -ng };
    let d = position - p0;
    let b1 = d.cross(e2).dot(cross_e) / area2;
    let b2 = e1.cross(d).dot(cross_e) / area2;
    let b = Vec3::new(1.0 - b1 - b2, b1, b2).max(Vec3::ZERO);
    let b = b / (b.x + b.y + b.z);
    let inside = b.x * p0 + b.y * p1 + b.z * p2;
    let mut lifted = inside;
    for (bk, pk, nk) in [(b.x, p0, n0), (b.y, p1, n1), (b.z, p2, n2)] {
        lifted -= bk * (inside - pk).dot(nk).min(0.0) * nk;
    }
    RaySurface {
        point: lifted,
        geometric_normal,
        front,
        own: None,
    }
}

/// visibility.glsl's `offset_ray_origin` (Wächter & Binder, Ray Tracing Gems ch. 6): 256 ulps of
/// each coordinate along `n`, or 2^-16 absolute within 1/32 of the world origin.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    let moved = |p: f32, n: f32| {
        // `as` truncates towards zero, like GLSL's ivec3(float).
        let ulps = (256.0 * n) as i32;
        let bits = p.to_bits() as i32;
        f32::from_bits(bits.wrapping_add(if p < 0.0 { -ulps } else { ulps }) as u32)
    };
    let pick = |p: f32, n: f32| {
        if p.abs() < 1.0 / 32.0 {
            p + n * (1.0 / 65536.0)
        } else {
            moved(p, n)
        }
    };
    Vec3::new(pick(p.x, n.x), pick(p.y, n.y), pick(p.z, n.z))
}

/// The light as the shader's `Frame::light_vector` holds it (f32, w = 0 directional, 1 point).
fn light_vector(light: &Light) -> (Vec3, bool) {
    match *light {
        Light::Directional { to_light, .. } => (to_light.as_vec3(), false),
        Light::Point { position, .. } => (position.as_vec3(), true),
    }
}

/// visibility.glsl's `light_visibility`: whether `light` is seen from `surface`.
pub fn light_visible(bvh: &SceneBvh, surface: &RaySurface, light: &Light) -> bool {
    let (vector, point) = light_vector(light);
    let towards = if point {
        vector - surface.point
    } else {
        vector
    };
    let side = if towards.dot(surface.geometric_normal) < 0.0 {
        -surface.geometric_normal
    } else {
        surface.geometric_normal
    };
    let origin = offset_ray_origin(surface.point, side);
    if !point {
        return !bvh.occluded_skipping(origin, vector.normalize(), (0.0, RAY_FAR), surface.own);
    }
    let to_light = vector - origin;
    let distance = to_light.length();
    !bvh.occluded_skipping(origin, to_light / distance, (0.0, distance), surface.own)
}

/// The scene as the twin traces it.
pub struct TracedScene<'a> {
    objects: &'a [TracedObject<'a>],
    bvh: SceneBvh,
    /// Per object, the sides its rays leave it by without meeting it ([`SelfHits`]), where the
    /// draw gives it an instance mask bit of its own (`own_mask_bits`), else none.
    clear: Vec<SelfHits>,
}

impl<'a> TracedScene<'a> {
    pub fn new(objects: &'a [TracedObject<'a>]) -> Self {
        let meshes: Vec<(&[[f32; 3]], &[u32])> = objects
            .iter()
            .map(|o| (o.mesh.positions.as_slice(), o.mesh.indices.as_slice()))
            .collect();
        let hits: Vec<(u32, SelfHits)> = objects
            .iter()
            .map(|o| {
                (
                    u32::try_from(o.mesh.triangle_count()).unwrap_or(u32::MAX),
                    SelfHits::of(o.mesh),
                )
            })
            .collect();
        let bits = own_mask_bits(hits.iter().copied());
        let clear = hits
            .iter()
            .zip(bits)
            .map(|(&(_, hits), bit)| if bit != 0 { hits } else { SelfHits::ANY })
            .collect();
        Self {
            objects,
            bvh: SceneBvh::new(&meshes),
            clear,
        }
    }

    /// `surface`, a point of `object`, with the object its rays never meet set
    /// (visibility.glsl's `trace_mask`).
    pub fn own(&self, object: usize, surface: RaySurface) -> RaySurface {
        let clear = self.clear[object];
        let leaves_clear = match surface.front {
            true => clear.front_clear,
            false => clear.back_clear,
        };
        RaySurface {
            own: leaves_clear.then_some(object as u32),
            ..surface
        }
    }

    pub fn bvh(&self) -> &SceneBvh {
        &self.bvh
    }

    pub fn objects(&self) -> &[TracedObject<'a>] {
        self.objects
    }

    /// One ray per pixel centre (SPEC §1); alpha 1 where it meets an object. `shadows`: lights
    /// with visibility, else every light seen (the image without ray tracing). No environment:
    /// [`Twin`](super::light_between::Twin) with its lights alone, no bounce.
    pub fn render(
        &self,
        camera: &Camera,
        lights: &[Light],
        size: (u32, u32),
        shadows: bool,
    ) -> HdrImage {
        let twin = super::light_between::Twin {
            scene: self,
            lights,
            environment: None,
            albedo: &[],
        };
        let rt = RayTracing {
            shadows,
            bounces: 0,
            rays: 1,
            seed: 0,
            denoise: false,
        };
        twin.render(camera, size, &rt)
    }
}
