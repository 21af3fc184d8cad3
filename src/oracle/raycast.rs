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
            let dir =
                scene
                    .camera
                    .primary_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, width, height);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The smooth-red material of SPEC §2 at r = 1: g(1) = 1.22 - 0.224 + 0.0199 = 1.0159.
    fn smooth_red() -> BrdfParams {
        BrdfParams {
            beckmann_m: 0.05,
            diffuse_a: -0.03,
            diffuse_b: 1.05,
            lacquer_g: 1.0159,
            albedo: [0.50, 0.06, 0.03],
        }
    }

    /// The default dispersive lacquer of SPEC §3 (A = 1.5, B = 0.0045 µm²): F ≈ 0.04 face-on.
    fn lacquer_fresnel() -> FresnelTable {
        FresnelTable::dielectric(1.5, 0.0045).unwrap()
    }

    fn assert_close(actual: DVec3, expected: DVec3, tolerance: f64) {
        let error = (actual - expected).abs().max_element();
        assert!(error <= tolerance, "{actual} vs {expected}: error {error}");
    }

    #[test]
    fn sphere_hit_from_default_eye_is_the_front_pole() {
        // a = 1, b' = -4, c = 15: roots 3 and 5, so t = 3 and the hit is exactly (0, 0, 1).
        let eye = DVec3::new(0.0, 0.0, 4.0);
        let hit = intersect(AnalyticShape::Sphere, eye, -DVec3::Z).unwrap();
        assert_eq!(hit.position, DVec3::Z);
        assert_eq!(hit.normal, DVec3::Z);
        // A non-unit direction gives the same point (t = 1.5 instead).
        let hit = intersect(AnalyticShape::Sphere, eye, DVec3::new(0.0, 0.0, -2.0)).unwrap();
        assert_eq!(hit.position, DVec3::Z);
    }

    #[test]
    fn sphere_misses_and_inside_hits() {
        let eye = DVec3::new(0.0, 0.0, 4.0);
        assert!(
            intersect(AnalyticShape::Sphere, eye, DVec3::Z).is_none(),
            "behind"
        );
        let above = DVec3::new(0.0, 1.01, 4.0);
        assert!(intersect(AnalyticShape::Sphere, above, -DVec3::Z).is_none());
        // From the centre the only root with t > 0 is the far wall, normal still outward.
        let hit = intersect(AnalyticShape::Sphere, DVec3::ZERO, DVec3::X).unwrap();
        assert_eq!(hit.position, DVec3::X);
        assert_eq!(hit.normal, DVec3::X);
    }

    #[test]
    fn sphere_hit_off_axis_matches_hand_solution() {
        // From (0, 0.6, 4) along -Z: x² + 0.36 + z² = 1 gives z = 0.8 exactly in reals.
        let hit = intersect(AnalyticShape::Sphere, DVec3::new(0.0, 0.6, 4.0), -DVec3::Z).unwrap();
        // 1e-15: two roundings in the quadratic.
        assert_close(hit.position, DVec3::new(0.0, 0.6, 0.8), 1e-15);
    }

    #[test]
    fn board_hits_inside_the_square_only() {
        let down = -DVec3::Y;
        let hit = intersect(AnalyticShape::Board, DVec3::new(0.5, 2.0, -0.3), down).unwrap();
        assert_eq!(hit.position, DVec3::new(0.5, 0.0, -0.3));
        assert_eq!(hit.normal, DVec3::Y);
        // Oblique: from (0, 1, 0) along (1, -1, 1)/√3 the plane is reached at (1, 0, 1), the corner.
        let corner = intersect(AnalyticShape::Board, DVec3::Y, DVec3::new(1.0, -1.0, 1.0));
        assert_eq!(corner.unwrap().position, DVec3::new(1.0, 0.0, 1.0));
        let outside = DVec3::new(1.5, 2.0, 0.0);
        assert!(intersect(AnalyticShape::Board, outside, down).is_none());
        assert!(
            intersect(AnalyticShape::Board, DVec3::Y, DVec3::X).is_none(),
            "parallel"
        );
        assert!(
            intersect(AnalyticShape::Board, DVec3::Y, DVec3::Y).is_none(),
            "away"
        );
        // The intersection is two-sided; shading makes the underside black.
        let below = intersect(AnalyticShape::Board, -DVec3::Y, DVec3::Y).unwrap();
        assert_eq!(below.normal, DVec3::Y);
    }

    #[test]
    fn diffuse_sphere_under_eye_light_matches_hand_computation() {
        // Default camera, 64×64, one directional light E = 1 from +Z (the eye's side).
        // Pixel (44, 32), worked by hand from SPEC §1 and §2 (independently of this code):
        //   x_ndc = (2·44.5/64 - 1)·tan 20° = 0.14217587, y_ndc = (1 - 65/64)·tan 20° = -0.00568703
        //   ray from (0,0,4) hits the unit sphere at P = (0.44113364, -0.01764535, 0.89726794)
        //   N = P, nl = N·Z = 0.89726794, nv = N·normalize(eye - P) = 0.82612791
        //   nh = 0.86385420 ⇒ Beckmann D(m = 0.05) ≈ 2e-57: the specular lobe is nil here.
        //   L = k_d·(a + b·nv)·g/π·nl = k_d·(-0.03 + 1.05·0.82612791)·1.0159/π·0.89726794
        //     = (0.121490967, 0.014578916, 0.007289458) for k_d = (0.5, 0.06, 0.03).
        let camera = Camera::default();
        let lights = [Light::Directional {
            to_light: DVec3::Z,
            irradiance: DVec3::ONE,
        }];
        let (brdf, fresnel) = (smooth_red(), lacquer_fresnel());
        let scene = OracleScene {
            shape: AnalyticShape::Sphere,
            camera: &camera,
            lights: &lights,
            brdf: &brdf,
            fresnel: &fresnel,
        };
        let image = render(&scene, 64, 64);
        let [r, g, b, alpha] = image.get(44, 32);
        assert_eq!(alpha, 1.0);
        let expected = DVec3::new(0.121490967, 0.014578916, 0.007289458);
        // f64 radiance from shade(): 2e-9, as the hand constants are rounded to 1e-9 absolute.
        let radiance = DVec3::from(shade(
            &scene,
            &intersect(
                scene.shape,
                camera.eye,
                camera.primary_ray(44.5, 32.5, 64, 64),
            )
            .unwrap(),
        ));
        assert_close(radiance, expected, 2e-9);
        let pixel = DVec3::new(f64::from(r), f64::from(g), f64::from(b));
        // f32 storage: half an ulp of 0.12 is 3.7e-9, plus the 1e-9 of the constants.
        assert_close(pixel, expected, 1e-8);
        // The corner ray (~27° off axis) misses the sphere (which subtends asin(1/4) ≈ 14.5°).
        assert_eq!(image.get(0, 0), [0.0; 4]);
    }

    #[test]
    fn board_seen_from_below_is_covered_but_black() {
        let camera = Camera {
            eye: DVec3::new(0.2, -3.0, 0.1),
            target: DVec3::ZERO,
            up: DVec3::Z,
            fov_deg: 40.0,
        };
        let lights = [Light::Directional {
            to_light: DVec3::new(0.0, -1.0, 0.3).normalize(),
            irradiance: DVec3::splat(5.0),
        }];
        let (brdf, fresnel) = (smooth_red(), lacquer_fresnel());
        let scene = OracleScene {
            shape: AnalyticShape::Board,
            camera: &camera,
            lights: &lights,
            brdf: &brdf,
            fresnel: &fresnel,
        };
        let image = render(&scene, 16, 16);
        assert_eq!(image.get(8, 8), [0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn point_light_radiance_falls_as_inverse_square() {
        // A point light straight above the board's centre at heights 1 and 2: L = +Y in both
        // cases, so f_r and nl are identical and the radiance ratio is exactly E ratio = 4.
        let camera = Camera {
            eye: DVec3::new(0.0, 2.0, 3.0),
            ..Camera::default()
        };
        let (brdf, fresnel) = (smooth_red(), lacquer_fresnel());
        let hit = SurfaceHit {
            position: DVec3::ZERO,
            normal: DVec3::Y,
        };
        let radiance_at = |height: f64| {
            let lights = [Light::Point {
                position: DVec3::new(0.0, height, 0.0),
                intensity: DVec3::splat(10.0),
            }];
            let scene = OracleScene {
                shape: AnalyticShape::Board,
                camera: &camera,
                lights: &lights,
                brdf: &brdf,
                fresnel: &fresnel,
            };
            DVec3::from(shade(&scene, &hit))
        };
        let (near, far) = (radiance_at(1.0), radiance_at(2.0));
        assert!(near.min_element() > 0.0);
        // Relative 1e-15: E = I/d² with d² = 1 and 4 is exact; only the final products round.
        assert_close(near / far, DVec3::splat(4.0), 4.0 * 1e-15);
    }

    #[test]
    fn lights_add_and_lights_behind_the_surface_add_nothing() {
        let camera = Camera::default();
        let (brdf, fresnel) = (smooth_red(), lacquer_fresnel());
        let key = Light::Directional {
            to_light: DVec3::new(-0.5, 0.7, 0.5).normalize(),
            irradiance: DVec3::new(3.0, 2.0, 1.0),
        };
        let behind = Light::Directional {
            to_light: -DVec3::Z,
            irradiance: DVec3::splat(100.0),
        };
        let hit = SurfaceHit {
            position: DVec3::new(0.0, 0.6, 0.8),
            normal: DVec3::new(0.0, 0.6, 0.8),
        };
        let shade_with = |lights: &[Light]| {
            let scene = OracleScene {
                shape: AnalyticShape::Sphere,
                camera: &camera,
                lights,
                brdf: &brdf,
                fresnel: &fresnel,
            };
            DVec3::from(shade(&scene, &hit))
        };
        let alone = shade_with(&[key]);
        assert!(alone.min_element() > 0.0);
        // Exact: the light behind (nl = -0.8) is skipped, adding +0.0 to every channel.
        assert_eq!(shade_with(&[key, behind]), alone);
        assert_eq!(shade_with(&[behind]), DVec3::ZERO);
        // Relative 1e-15: two lights are one sum of two rounded terms.
        assert_close(
            shade_with(&[key, key]),
            2.0 * alone,
            1e-15 * alone.max_element(),
        );
    }
}
