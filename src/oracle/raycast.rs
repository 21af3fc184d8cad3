//! The CPU reference renderer: one ray per pixel centre against the exact analytic shape, shaded
//! with `model::lacquer_brdf` under the punctual lights. Tests compare the GPU image to this.
//!
//! Clarity over speed, f64 throughout. It uses the same [`Camera`] and [`Light`] values as the
//! GPU draw but none of its code (no matrices, no tessellation), so the two are independent.
//! No shadows: the sphere is convex and the board flat, so neither can shadow itself.

use glam::DVec3;

use crate::model::{lacquer_brdf, BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::{Camera, Light};

/// The exact shapes behind the built-in meshes of SPEC §5.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnalyticShape {
    /// Unit sphere at the origin.
    Sphere,
    /// The square |x| <= 1, |z| <= 1 at y = 0; normal +Y, visible from above only.
    Board,
}

/// Where a ray meets the surface, with the outward (sphere) or +Y (board) unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub position: DVec3,
    pub normal: DVec3,
}

/// The nearest intersection at ray parameter t > 0 of `origin + t·dir` with `shape`
/// (`dir` need not be unit).
pub fn intersect(shape: AnalyticShape, origin: DVec3, dir: DVec3) -> Option<SurfaceHit> {
    match shape {
        AnalyticShape::Sphere => intersect_unit_sphere(origin, dir),
        AnalyticShape::Board => intersect_board(origin, dir),
    }
}

/// |o + t·d|² = 1  ⇔  (d·d)t² + 2(o·d)t + (o·o - 1) = 0. The roots are formed as q/a and c/q
/// with q = -(b' + sign(b')·√disc), b' = o·d, which avoids cancellation at grazing rays.
fn intersect_unit_sphere(origin: DVec3, dir: DVec3) -> Option<SurfaceHit> {
    let a = dir.dot(dir);
    let half_b = origin.dot(dir);
    let c = origin.dot(origin) - 1.0;
    let discriminant = half_b * half_b - a * c;
    if a == 0.0 || discriminant < 0.0 {
        return None;
    }
    let q = -(half_b + half_b.signum() * discriminant.sqrt());
    let (t0, t1) = if q == 0.0 {
        // Origin on the sphere's centre plane with a tangent ray: a double root at 0.
        (0.0, 0.0)
    } else {
        let (r0, r1) = (q / a, c / q);
        (r0.min(r1), r0.max(r1))
    };
    let t = if t0 > 0.0 { t0 } else { t1 };
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let position = origin + t * dir;
    Some(SurfaceHit {
        position,
        normal: position.normalize(),
    })
}

fn intersect_board(origin: DVec3, dir: DVec3) -> Option<SurfaceHit> {
    if dir.y == 0.0 {
        return None;
    }
    let t = -origin.y / dir.y;
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let position = DVec3::new(origin.x + t * dir.x, 0.0, origin.z + t * dir.z);
    if position.x.abs() > 1.0 || position.z.abs() > 1.0 {
        return None;
    }
    Some(SurfaceHit {
        position,
        normal: DVec3::Y,
    })
}

/// Everything the reference renderer reads; borrowed so tests can vary one part at a time.
pub struct OracleScene<'a> {
    pub shape: AnalyticShape,
    pub camera: &'a Camera,
    pub lights: &'a [Light],
    pub brdf: &'a BrdfParams,
    pub fresnel: &'a FresnelTable,
}

/// One sample per pixel at the pixel centre. Alpha is 1 where the centre ray hits the shape
/// (even where the surface faces away and shades black), else the pixel is (0, 0, 0, 0).
pub fn render(scene: &OracleScene, width: u32, height: u32) -> HdrImage {
    let mut image = HdrImage::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let dir = scene.camera.primary_ray(
                f64::from(x) + 0.5,
                f64::from(y) + 0.5,
                width,
                height,
            );
            let rgba = match intersect(scene.shape, scene.camera.eye, dir) {
                Some(hit) => {
                    let [r, g, b] = shade(scene, &hit);
                    [r as f32, g as f32, b as f32, 1.0]
                }
                None => [0.0; 4],
            };
            image.set(x, y, rgba);
        }
    }
    image
}

/// Radiance leaving `hit` towards the camera's eye: Σ_lights f_r(N, V, L)·E·max(N·L, 0)
/// (SPEC §2: "reflected radiance from a light with irradiance E at normal incidence is f_r·E·nl").
pub fn shade(scene: &OracleScene, hit: &SurfaceHit) -> [f64; 3] {
    let n = hit.normal;
    let v = (scene.camera.eye - hit.position).normalize();
    // Seen from behind (the board from below): SPEC §2 makes the BRDF 0 for nv <= 0.
    let nv = n.dot(v);
    if nv.is_nan() || nv <= 0.0 {
        return [0.0; 3];
    }
    let mut radiance = DVec3::ZERO;
    for light in scene.lights {
        let Some((l, irradiance)) = light.incident_at(hit.position) else {
            continue;
        };
        let nl = n.dot(l);
        if nl <= 0.0 {
            continue;
        }
        let f_r = DVec3::from(lacquer_brdf(scene.brdf, scene.fresnel, n, v, l));
        radiance += f_r * irradiance * nl;
    }
    radiance.to_array()
}
