//! The CPU twin of SPEC §6's integral as the ray-traced shading pass estimates it
//! (`shaders/common/light_between.glsl`, `sequence.glsl`): the same sample sequence bit for bit,
//! the same lobe sampling and mixture pdf, the same paths, over the same triangles (a
//! [`TracedScene`]). Directions are formed in f32 like the shader's; the BRDF is
//! `model::lacquer_brdf` in f64.
//!
//! The environment is constant (radiance `c` from every direction), for which both environment
//! models, and the hidden environment the shader reads from the layers at each sample's
//! footprint, have exact values the twin can state without the GPU's cube filtering: `paper` gives
//! F(acos nv)·c, `brdf` gives A(nv)·c from the albedo knots the draw uses; the diffuse half is
//! f_diff·E_irr, E_irr the irradiance the caller passes (the GPU's irradiance cube holds π·c to
//! its quadrature's accuracy). The control variate of the hidden environment takes the `brdf`
//! model's value in either model.

use glam::{DVec3, Vec3};

use super::bvh::BvhHit;
use super::shadows::{light_visible, offset_ray_origin, ray_surface, RaySurface, TracedScene};
use super::visible_normals::{beckmann_g1, sample_visible_normal, visible_normal_pdf};
use crate::environment::brdf_quadrature::albedo_at;
use crate::environment::EnvironmentModel;
use crate::model::brdf::{beckmann_d, view_dependent_diffuse};
use crate::model::lacquer_brdf;
use crate::output::HdrImage;
use crate::raster::draw::RayTracing;
use crate::raster::{Camera, Light};

/// `sequence.glsl`, bit for bit.
pub mod sequence {
    /// Wellons' lowbias32.
    pub fn hash_u32(mut x: u32) -> u32 {
        x ^= x >> 16;
        x = x.wrapping_mul(0x7feb_352d);
        x ^= x >> 15;
        x = x.wrapping_mul(0x846c_a68b);
        x ^= x >> 16;
        x
    }

    /// [0, 1) from the top 24 bits.
    pub fn unit_from_bits(x: u32) -> f32 {
        (x >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    pub fn radical_inverse_2(i: u32) -> f32 {
        unit_from_bits(i.reverse_bits())
    }

    pub fn radical_inverse_3(mut i: u32) -> f32 {
        let (mut mirrored, mut scale) = (0u32, 1u32);
        let mut k = 0;
        while k < 20 && i > 0 {
            mirrored = mirrored * 3 + i % 3;
            i /= 3;
            scale *= 3;
            k += 1;
        }
        mirrored as f32 / scale as f32
    }

    pub fn pixel_key(x: u32, y: u32, seed: u32) -> u32 {
        hash_u32(y ^ hash_u32(x ^ hash_u32(seed)))
    }

    fn fract(x: f32) -> f32 {
        x - x.floor()
    }

    /// The number that picks the light at ray `ray`'s hit at bounce `depth`.
    pub fn light_number(key: u32, ray: u32, depth: u32) -> f32 {
        let h = hash_u32(key ^ hash_u32(ray.wrapping_mul(8).wrapping_add(depth)));
        unit_from_bits(hash_u32(h.wrapping_add(3)))
    }

    /// Three numbers in [0, 1) for ray `ray` of `rays` at bounce `depth`.
    pub fn sample_numbers(key: u32, ray: u32, rays: u32, depth: u32) -> [f32; 3] {
        if depth == 0 {
            let shift = [
                unit_from_bits(hash_u32(key)),
                unit_from_bits(hash_u32(key ^ 0x9e37_79b9)),
                unit_from_bits(hash_u32(key ^ 0x7f4a_7c15)),
            ];
            let point = [
                (ray as f32 + 0.5) / rays as f32,
                radical_inverse_2(ray),
                radical_inverse_3(ray),
            ];
            return std::array::from_fn(|k| fract(point[k] + shift[k]));
        }
        let h = hash_u32(key ^ hash_u32(ray.wrapping_mul(8).wrapping_add(depth)));
        [
            unit_from_bits(hash_u32(h)),
            unit_from_bits(hash_u32(h.wrapping_add(1))),
            unit_from_bits(hash_u32(h.wrapping_add(2))),
        ]
    }
}

/// A constant environment as the twin shades it.
#[derive(Clone, Copy, Debug)]
pub struct ConstantEnvironment {
    /// c: the radiance from every direction (after intensity).
    pub radiance: [f64; 3],
    /// E_irr: what the draw's irradiance cube holds (π·c up to its quadrature).
    pub irradiance: [f64; 3],
    pub model: EnvironmentModel,
}

/// One object's albedo knots (the `brdf` model's A(nv)), as the draw computes them.
pub type AlbedoKnots = Vec<[f32; 4]>;

/// A surface point of the twin: object, triangle, where rays leave, shading frame.
struct Point {
    object: usize,
    position: Vec3,
    normal: Vec3,
    view: Vec3,
    surface: RaySurface,
}

/// The scene, lights and environment the twin traces.
pub struct Twin<'a> {
    pub scene: &'a TracedScene<'a>,
    pub lights: &'a [Light],
    pub environment: Option<ConstantEnvironment>,
    /// Per object: the `brdf` model's A(nv), read in either model by the control variate.
    pub albedo: &'a [AlbedoKnots],
}

impl Twin<'_> {
    /// One ray per pixel centre; alpha 1 where it meets an object. `rt`: what the draw traces.
    pub fn render(
        &self,
        camera: &Camera,
        (width, height): (u32, u32),
        rt: &RayTracing,
    ) -> HdrImage {
        self.render_with_integral(camera, (width, height), rt).0
    }

    /// [`render`](Self::render) and the integral image of the draw's
    /// `LacquerRenderer::render_with_integral`: rgb the integral's estimate (before the clamp),
    /// alpha the variance of its grey value, −1 where no object is met.
    pub fn render_with_integral(
        &self,
        camera: &Camera,
        (width, height): (u32, u32),
        rt: &RayTracing,
    ) -> (HdrImage, HdrImage) {
        let mut image = HdrImage::new(width, height);
        let mut integral = HdrImage::new(width, height);
        let eye = camera.eye.as_vec3();
        for y in 0..height {
            for x in 0..width {
                integral.set(x, y, [0.0, 0.0, 0.0, -1.0]);
                let dir = camera.primary_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, width, height);
                let Some(hit) = self
                    .scene
                    .bvh()
                    .intersect(eye, dir.as_vec3(), 0.0, f32::INFINITY)
                else {
                    continue;
                };
                let (position, normal) = self.surface_at(&hit);
                let view = (eye - position).normalize();
                let point = self.point(&hit, position, normal, view);
                let (mut radiance, environment) = self.radiance_towards(&point, rt.shadows, None);
                let mut added = [0.0f32; 4];
                if rt.bounces > 0 {
                    let key = sequence::pixel_key(x, y, rt.seed);
                    let environment = self.integral_environment(&point, environment);
                    let (estimate, variance) = self.light_between(&point, key, rt, environment);
                    let [r, g, b] = estimate.to_array();
                    added = [r as f32, g as f32, b as f32, variance as f32];
                    // As the draw: a radiance below 0 is clamped (after the integral image).
                    radiance = (radiance + estimate).max(DVec3::ZERO);
                }
                let [r, g, b] = radiance.to_array();
                image.set(x, y, [r as f32, g as f32, b as f32, 1.0]);
                integral.set(x, y, added);
            }
        }
        (image, integral)
    }

    /// The point and shading normal of ray_surface.glsl's `hit_surface`.
    fn surface_at(&self, hit: &BvhHit) -> (Vec3, Vec3) {
        let mesh = self.scene.objects()[hit.object as usize].mesh;
        let [(p0, n0), (p1, n1), (p2, n2)] = [0, 1, 2].map(|k| {
            let index = mesh.indices[3 * hit.triangle as usize + k] as usize;
            (
                Vec3::from(mesh.positions[index]),
                Vec3::from(mesh.normals[index]),
            )
        });
        let [u, v] = hit.barycentrics;
        let w = 1.0 - u - v;
        (
            w * p0 + u * p1 + v * p2,
            (w * n0 + u * n1 + v * n2).normalize(),
        )
    }

    fn point(&self, hit: &BvhHit, position: Vec3, normal: Vec3, view: Vec3) -> Point {
        let mesh = self.scene.objects()[hit.object as usize].mesh;
        Point {
            object: hit.object as usize,
            position,
            normal,
            view,
            surface: self.scene.own(
                hit.object as usize,
                ray_surface(mesh, hit.triangle, position, normal),
            ),
        }
    }

    /// Light `light`'s f_r·E·(N·L) at the point, unshadowed (lacquer_shade.glsl's
    /// `unshadowed_light`).
    fn unshadowed_light(&self, point: &Point, light: &Light) -> DVec3 {
        let object = &self.scene.objects()[point.object];
        let (n, v) = (point.normal.as_dvec3(), point.view.as_dvec3());
        let Some((l, irradiance)) = light.incident_at(point.position.as_dvec3()) else {
            return DVec3::ZERO;
        };
        let nl = n.dot(l);
        if nl <= 0.0 {
            return DVec3::ZERO;
        }
        DVec3::from(lacquer_brdf(object.brdf, object.fresnel, n, v, l)) * irradiance * nl
    }

    /// lacquer_shade.glsl's `one_light`: one light chosen by `choice` with probability ∝ its
    /// unshadowed contribution (summed over r, g, b), weighted back by the total.
    fn one_light(&self, point: &Point, choice: f32) -> DVec3 {
        let contributions: Vec<DVec3> = self
            .lights
            .iter()
            .map(|light| self.unshadowed_light(point, light))
            .collect();
        let weight = |c: &DVec3| c.x + c.y + c.z;
        let total: f64 = contributions.iter().map(weight).sum();
        if total.is_nan() || total <= 0.0 {
            return DVec3::ZERO;
        }
        let target = f64::from(choice) * total;
        let mut below = 0.0;
        let last = contributions.len() - 1;
        for (i, (c, light)) in contributions.iter().zip(self.lights).enumerate() {
            let w = weight(c);
            below += w;
            if w > 0.0 && (target < below || i == last) {
                let visible = light_visible(self.scene.bvh(), &point.surface, light);
                return match visible {
                    true => *c * (total / w),
                    false => DVec3::ZERO,
                };
            }
        }
        DVec3::ZERO
    }

    /// lacquer_shade.glsl's `lacquer_radiance_towards`: lights with visibility (or without,
    /// `shadows` false; one light by next-event estimation with `light_choice`) plus the
    /// environment model; and that environment term's share.
    fn radiance_towards(
        &self,
        point: &Point,
        shadows: bool,
        light_choice: Option<f32>,
    ) -> (DVec3, DVec3) {
        let object = &self.scene.objects()[point.object];
        let (n, v) = (point.normal.as_dvec3(), point.view.as_dvec3());
        let nv = n.dot(v);
        if nv.is_nan() || nv <= 0.0 {
            return (DVec3::ZERO, DVec3::ZERO);
        }
        let lights = match light_choice {
            Some(choice) => self.one_light(point, choice),
            None => self
                .lights
                .iter()
                .filter(|light| !shadows || light_visible(self.scene.bvh(), &point.surface, light))
                .map(|light| self.unshadowed_light(point, light))
                .sum(),
        };
        let Some(env) = self.environment else {
            return (lights, DVec3::ZERO);
        };
        let c = DVec3::from(env.radiance);
        let specular = match env.model {
            EnvironmentModel::Paper => {
                DVec3::from(object.fresnel.eval(nv.min(1.0).acos().to_degrees())) * c
            }
            EnvironmentModel::Brdf => DVec3::from(albedo_at(&self.albedo[point.object], nv)) * c,
        };
        let f_diff = DVec3::from(view_dependent_diffuse(object.brdf, nv));
        let environment = specular + f_diff * DVec3::from(env.irradiance);
        (lights + environment, environment)
    }

    /// lacquer_shade.glsl's `integral_environment`: ∫ f_r·L·(N·s) dω over every direction at the
    /// point, the control variate's E. In `brdf` the model's term (`environment`); in `paper`
    /// the `brdf` model's quadrature, which a constant sky makes A(nv)·c (the quadrature is
    /// normalised by A) plus the diffuse half.
    fn integral_environment(&self, point: &Point, environment: DVec3) -> DVec3 {
        let Some(env) = self.environment else {
            return DVec3::ZERO;
        };
        if env.model == EnvironmentModel::Brdf {
            return environment;
        }
        let object = &self.scene.objects()[point.object];
        let nv = point.normal.as_dvec3().dot(point.view.as_dvec3());
        if nv.is_nan() || nv <= 0.0 {
            return DVec3::ZERO;
        }
        let c = DVec3::from(env.radiance);
        let specular = DVec3::from(albedo_at(&self.albedo[point.object], nv)) * c;
        let f_diff = DVec3::from(view_dependent_diffuse(object.brdf, nv));
        specular + f_diff * DVec3::from(env.irradiance)
    }

    /// light_between.glsl's `light_between`: the mean over the rays and the variance of its grey
    /// value. `environment`: the primary point's
    /// [`integral_environment`](Self::integral_environment) E. Each ray also adds h_i·(c_i − E),
    /// c_i its first bounce's w·L(s) and h_i the share of the other rays whose first bounce met
    /// an object (the shader's comment derives it).
    fn light_between(
        &self,
        primary: &Point,
        key: u32,
        rt: &RayTracing,
        environment: DVec3,
    ) -> (DVec3, f64) {
        let hidden = self
            .environment
            .map_or(DVec3::ZERO, |env| DVec3::from(env.radiance));
        let grey = |c: DVec3| (c.x + c.y + c.z) / 3.0;
        // Per ray: its path, its first bounce's d_i = c_i − E, whether that bounce met an object.
        let mut rays = Vec::with_capacity(rt.rays as usize);
        for i in 0..rt.rays {
            let mut path = DVec3::ZERO;
            let mut throughput = DVec3::ONE;
            let mut at = Point { ..*primary };
            let (mut c, mut hit_first) = (DVec3::ZERO, false);
            for depth in 0..rt.bounces {
                let u = sequence::sample_numbers(key, i, rt.rays, depth);
                let Some((s, weight)) = self.sample_lobes(&at, u) else {
                    break;
                };
                if depth == 0 {
                    c = weight * hidden;
                }
                let ng = at.surface.geometric_normal;
                let side = if s.dot(ng) < 0.0 { -ng } else { ng };
                let origin = offset_ray_origin(at.surface.point, side);
                let skip = at.surface.own;
                let Some(hit) = self.scene.bvh().intersect_skipping(origin, s, skip) else {
                    break;
                };
                hit_first |= depth == 0;
                let (position, normal) = self.surface_at(&hit);
                at = self.point(&hit, position, normal, -s);
                let choice = rt.shadows.then(|| sequence::light_number(key, i, depth));
                let (radiance, _) = self.radiance_towards(&at, rt.shadows, choice);
                path += throughput * weight * (radiance - hidden);
                throughput *= weight;
            }
            rays.push((path, c - environment, hit_first));
        }
        let n = f64::from(rt.rays.max(1));
        let hits = rays.iter().filter(|ray| ray.2).count() as f64;
        let blend = rt.rays > 1 && hits > 0.0;
        let (mut total, mut moments) = (DVec3::ZERO, (0.0, 0.0));
        for &(path, d, hit) in &rays {
            let share = match blend {
                true => (hits - f64::from(u8::from(hit))) / (n - 1.0),
                false => 0.0,
            };
            let value = path + share * d;
            total += value;
            moments = (moments.0 + grey(value), moments.1 + grey(value).powi(2));
        }
        (total / n, sample_variance_of_mean(moments, n))
    }

    /// light_between.glsl's `sample_lobes`: the direction (f32, as the shader forms it) and the
    /// weight f_r·(N·s)/pdf (f64).
    fn sample_lobes(&self, at: &Point, u: [f32; 3]) -> Option<(Vec3, DVec3)> {
        let object = &self.scene.objects()[at.object];
        let (n, v) = (at.normal, at.view);
        let nv = n.dot(v);
        if nv <= 0.0 {
            return None;
        }
        let f_diff = view_dependent_diffuse(object.brdf, f64::from(nv));
        let f = object
            .fresnel
            .eval(f64::from(nv.min(1.0)).acos().to_degrees());
        let specular = f.iter().sum::<f64>() as f32;
        let diffuse = (f_diff.iter().sum::<f64>() * std::f64::consts::PI) as f32;
        let p_specular = (specular / (specular + diffuse).max(1e-30)).clamp(0.1, 0.9);
        let (t, b) = tangent_frame(n);
        let m = object.brdf.beckmann_m;
        let s = if u[0] < p_specular {
            let v_local = Vec3::new(v.dot(t), v.dot(b), nv);
            let h = sample_visible_normal(v_local, m as f32, [u[1], u[2]]);
            let h = t * h.x + b * h.y + n * h.z;
            2.0 * v.dot(h) * h - v
        } else {
            let phi = 2.0 * std::f32::consts::PI * u[2];
            (t * phi.cos() + b * phi.sin()) * u[1].sqrt() + n * (1.0 - u[1]).max(0.0).sqrt()
        };
        let ns = n.dot(s);
        if ns <= 0.0 {
            return None;
        }
        let (nd, vd, sd) = (n.as_dvec3(), v.as_dvec3(), s.as_dvec3());
        let h = (vd + sd).normalize();
        let (nh, vh) = (nd.dot(h), vd.dot(h));
        let nv = f64::from(nv);
        let pdf_specular = match nh > 0.0 {
            true => visible_normal_pdf(beckmann_d(nh, m), beckmann_g1(nv, m), nv, vh),
            false => 0.0,
        };
        let p_specular = f64::from(p_specular);
        let pdf =
            p_specular * pdf_specular + (1.0 - p_specular) * f64::from(ns) / std::f64::consts::PI;
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let f_r = DVec3::from(lacquer_brdf(object.brdf, object.fresnel, nd, vd, sd));
        Some((s, f_r * (f64::from(ns) / pdf)))
    }
}

/// light_between.glsl's `tangent_frame` (Duff et al.).
fn tangent_frame(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let c = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x),
        Vec3::new(c, sign + n.y * n.y * a, -n.y),
    )
}

/// math.glsl's `sample_variance_of_mean`: the variance of the mean of `n` samples from their sums
/// (Σx, Σx²), unbiased; with one sample, its square.
pub fn sample_variance_of_mean((sum, squares): (f64, f64), n: f64) -> f64 {
    if n < 2.0 {
        return sum * sum;
    }
    (squares - sum * sum / n).max(0.0) / (n * (n - 1.0))
}

#[cfg(test)]
mod tests {
    use super::sequence::*;

    #[test]
    fn the_variance_of_a_mean_is_the_sample_variance_over_n() {
        use super::sample_variance_of_mean;
        // 1, 2, 3, 4: sample variance 5/3, of the mean 5/12.
        let v = sample_variance_of_mean((10.0, 30.0), 4.0);
        assert!((v - 5.0 / 12.0).abs() < 1e-15, "{v}");
        // Equal samples: none; one sample: its square.
        assert_eq!(sample_variance_of_mean((6.0, 12.0), 3.0), 0.0);
        assert_eq!(sample_variance_of_mean((-0.5, 0.25), 1.0), 0.25);
    }

    #[test]
    fn radical_inverses_are_the_van_der_corput_sequences() {
        assert_eq!(radical_inverse_2(0), 0.0);
        assert_eq!(radical_inverse_2(1), 0.5);
        assert_eq!(radical_inverse_2(2), 0.25);
        assert_eq!(radical_inverse_2(3), 0.75);
        assert_eq!(radical_inverse_3(1), 1.0 / 3.0);
        assert_eq!(radical_inverse_3(2), 2.0 / 3.0);
        assert_eq!(radical_inverse_3(3), 1.0 / 9.0);
        assert_eq!(radical_inverse_3(5), 7.0 / 9.0);
    }

    #[test]
    fn first_bounce_numbers_are_stratified_per_pixel() {
        let rays = 16;
        let key = pixel_key(7, 9, 3);
        let mut first: Vec<f32> = (0..rays)
            .map(|i| sample_numbers(key, i, rays, 0)[0])
            .collect();
        first.sort_by(f32::total_cmp);
        // One number in each of the 16 strata (a rotation modulo 1 keeps the spacing).
        for (k, x) in first.windows(2).enumerate() {
            let gap = x[1] - x[0];
            assert!((gap - 1.0 / 16.0).abs() < 1e-6, "gap {k}: {gap}");
        }
        assert_ne!(pixel_key(7, 9, 3), pixel_key(9, 7, 3));
        assert_ne!(pixel_key(7, 9, 3), pixel_key(7, 9, 4));
    }
}
