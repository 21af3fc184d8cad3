//! A brute-force CPU path tracer of SPEC §6 under a constant environment: the ground truth that
//! the GPU's light-between-objects estimator must converge to.
//!
//! Why it exists: the GPU evaluates SPEC §6 in its "difference" form (the environment model plus
//! a correction integral over the directions that meet an object). This module computes the same
//! quantity as the plain path-traced rendering equation instead, so that an error in that
//! rewriting, in the GPU's sampling or in its pdf cannot be shared by the reference:
//!
//! ```text
//! L(x, V, depth) = Σ_lights f_r·E·(N·L)·vis(x, L)
//!                + [depth == B+1 ? L_env_model(x, V) : E_s[ f_r(N,V,s)·L_in(x,s)·(N·s) / pdf(s) ]]
//! L_in(x, s)     = L(y, −s, depth+1) if the ray from x along s first meets an object at y, else c
//! ```
//!
//! with depth 1 at the primary hit and B = `bounces`. One direction is drawn per path and level
//! (the recursion never branches), `samples_per_pixel` paths per pixel are averaged.
//!
//! Scope and simplifications, all deliberate:
//! - The environment model is SPEC §4's `brdf` model, L_env_model(x, V) = ∫ f_r·L(s)·(N·s) dω:
//!   the whole environment reflected, with no visibility. Two kinds of environment
//!   ([`PathEnvironment`]):
//!   - a constant radiance `c` (RGB), under which that model is exact in closed form:
//!     L_env_model(x, V) = c·A_spec(nv) + f_diff(nv)·π·c (E_irr = π·c), where A_spec is the
//!     directional albedo of the specular term, tabulated per material (see [`AlbedoTable`]);
//!   - an equirectangular map (a real HDRI), piecewise constant over its pixels (`map_sampler`).
//!     Every level then also draws a direction from the map (next-event estimation, with a
//!     shadow ray below the last level) and combines it with the BRDF's draw by multiple
//!     importance sampling (balance heuristic), and the last level estimates L_env_model with
//!     the same two draws, unoccluded, instead of a closed form.
//! - Directions are drawn from a 50/50 mixture of cosine-weighted hemisphere sampling and
//!   Beckmann half-vector sampling, weighted by the mixture pdf (one-sample MIS with the balance
//!   heuristic). The sampler is written here and shares nothing with the GPU's.
//! - Maths is f64; only the ray queries are f32, through the same [`SceneBvh`] and the same
//!   ray-origin offset (`offset_ray_origin`) as the ray-traced shading pass's CPU twin. Rays
//!   leave from the interpolated point on the flat triangle (no shadow-terminator lift): this is
//!   the rendering equation of the triangles themselves.
//! - Deterministic: each pixel has its own SplitMix64 stream seeded by (seed, pixel index), so
//!   the image does not depend on how rows are spread over threads.
//! - No anti-aliasing (one primary ray through each pixel centre); a pixel that shows no object
//!   is transparent black, [0, 0, 0, 0].

use std::f64::consts::{PI, TAU};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{DVec3, Vec3};

use super::bvh::{BvhHit, SceneBvh};
use super::map_sampler::MapSampler;
use super::shadows::{offset_ray_origin, TracedObject};
use crate::environment::brdf_definition::specular_albedo;
use crate::environment::{EnvironmentLight, Equirect};
use crate::model::brdf::view_dependent_diffuse;
use crate::model::{lacquer_brdf, BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::{Camera, Light};

/// Far enough for a directional light's shadow ray (as the GPU's `RAY_FAR`).
const RAY_FAR: f32 = 1e30;

/// The probability of drawing a direction from the cosine lobe rather than the Beckmann lobe.
/// One half covers both ends: the diffuse term (all of rough lacquer's colour) and the sharp
/// highlight of smooth lacquer each get at least half the samples they would get alone.
const COSINE_WEIGHT: f64 = 0.5;

/// Knots of the A_spec(nv) table, evenly spaced in nv over [0, 1].
const ALBEDO_KNOTS: usize = 256;

/// Midpoint steps in u (the Beckmann lobe's cumulative distribution) and in φ of each knot's
/// `specular_albedo` quadrature. See [`AlbedoTable`] for the accuracy this buys.
const ALBEDO_STEPS: u32 = 128;

/// What the path tracer renders: world-space objects, the camera, punctual lights and the
/// environment.
pub struct PathScene<'a> {
    pub objects: &'a [TracedObject<'a>],
    pub camera: &'a Camera,
    pub lights: &'a [Light],
    pub environment: PathEnvironment<'a>,
}

/// The light a path meets when it leaves the objects (module doc).
#[derive(Clone, Copy)]
pub enum PathEnvironment<'a> {
    /// Constant radiance c (RGB, linear; zero for none).
    Constant([f64; 3]),
    /// An equirectangular map (SPEC §1), turned and scaled by `light` as SPEC §4 has it.
    Map {
        image: &'a Equirect,
        light: EnvironmentLight,
    },
}

/// The path tracer's result: the mean image and, per pixel (row-major like `mean.pixels`), the
/// standard error of that mean, the largest over the three channels. Tests use the error to tell
/// Monte-Carlo noise from bias. It is 0 where the value has no noise (no object seen, or
/// `bounces` = 0 under a constant environment) and infinite where one path cannot estimate it
/// (`samples_per_pixel` = 1 where paths are sampled).
pub struct PathImage {
    pub mean: HdrImage,
    pub std_error: Vec<f64>,
}

impl PathImage {
    /// The image's own noise as a whole-image relative RMSE, √(Σ 3·σ² / Σ |mean|²) over the
    /// covered pixels (σ the largest channel's standard error, so an upper bound): what a
    /// comparison with it takes out in quadrature.
    pub fn relative_noise(&self) -> f64 {
        let (mut noise, mut norm) = (0.0, 0.0);
        for (pixel, error) in self.mean.pixels.iter().zip(&self.std_error) {
            if pixel[3] > 0.0 {
                noise += 3.0 * error * error;
                norm += pixel[..3]
                    .iter()
                    .map(|&c| f64::from(c).powi(2))
                    .sum::<f64>();
            }
        }
        (noise / norm).sqrt()
    }
}

/// Renders `scene` at `width × height` with `bounces` (B) reflections sampled before the
/// environment model closes the path, averaging `samples_per_pixel` paths per pixel (at least
/// one; with B = 0 under a constant environment nothing is sampled and one path is exact). The
/// same `seed` gives the same
/// image, bit for bit, on any number of threads.
pub fn render(
    scene: &PathScene,
    (width, height): (u32, u32),
    bounces: u32,
    samples_per_pixel: u32,
    seed: u64,
) -> PathImage {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    render_on_threads(
        scene,
        (width, height),
        bounces,
        samples_per_pixel,
        seed,
        threads,
    )
}

/// [`render`] on a given number of threads (tests check the image does not depend on it).
fn render_on_threads(
    scene: &PathScene,
    (width, height): (u32, u32),
    bounces: u32,
    samples_per_pixel: u32,
    seed: u64,
    threads: usize,
) -> PathImage {
    let tracer = Tracer::new(scene, bounces, threads);
    // With no bounce to sample under a constant environment every path is the same
    // deterministic value.
    let exact = bounces == 0 && tracer.map.is_none();
    let paths = if exact { 1 } else { samples_per_pixel.max(1) };
    let rows = parallel_map(height as usize, threads, |y| {
        (0..width)
            .map(|x| tracer.pixel(x, y as u32, (width, height), paths, seed))
            .collect::<Vec<_>>()
    });
    let mut mean = HdrImage::new(width, height);
    let mut std_error = Vec::with_capacity(width as usize * height as usize);
    for (y, row) in rows.into_iter().enumerate() {
        for (x, pixel) in row.into_iter().enumerate() {
            if let Some(stats) = pixel {
                let m = stats.mean;
                mean.set(
                    x as u32,
                    y as u32,
                    [m[0] as f32, m[1] as f32, m[2] as f32, 1.0],
                );
                std_error.push(if exact { 0.0 } else { stats.std_error() });
            } else {
                std_error.push(0.0);
            }
        }
    }
    PathImage { mean, std_error }
}

/// `f(0), …, f(count - 1)` computed on up to `threads` scoped threads that take indices from a
/// shared counter (so a slow row does not hold up the others), returned in index order.
fn parallel_map<T: Send>(count: usize, threads: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let next = AtomicUsize::new(0);
    let workers = threads.clamp(1, count.max(1));
    let mut indexed: Vec<(usize, T)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        if i >= count {
                            return done;
                        }
                        done.push((i, f(i)));
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|handle| {
                // A worker only fails by panicking; pass the panic on unchanged.
                handle
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            })
            .collect()
    });
    indexed.sort_by_key(|&(i, _)| i);
    indexed.into_iter().map(|(_, value)| value).collect()
}

/// The running mean and spread of one pixel's path values (Welford's update, per channel).
struct PixelStats {
    count: u32,
    mean: [f64; 3],
    /// Σ (x - mean)², per channel.
    squares: [f64; 3],
}

impl PixelStats {
    fn new() -> Self {
        Self {
            count: 0,
            mean: [0.0; 3],
            squares: [0.0; 3],
        }
    }

    fn add(&mut self, value: DVec3) {
        self.count += 1;
        let n = f64::from(self.count);
        for (c, x) in value.to_array().into_iter().enumerate() {
            let delta = x - self.mean[c];
            self.mean[c] += delta / n;
            self.squares[c] += delta * (x - self.mean[c]);
        }
    }

    /// The standard error of the mean, the largest over the channels; infinite for one path.
    fn std_error(&self) -> f64 {
        if self.count < 2 {
            return f64::INFINITY;
        }
        let n = f64::from(self.count);
        self.squares
            .iter()
            .map(|&s| (s.max(0.0) / (n * (n - 1.0))).sqrt())
            .fold(0.0, f64::max)
    }
}

/// A small, fast, well-mixed generator (Steele, Lea & Flood's SplitMix64). Each pixel gets its
/// own stream, so pixels do not depend on the order they are computed in.
struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

    /// The stream of pixel `pixel` for `seed`: the finaliser applied twice keeps neighbouring
    /// pixels and neighbouring seeds far apart in the state space.
    fn for_pixel(seed: u64, pixel: u64) -> Self {
        Self {
            state: mix64(seed ^ mix64(pixel.wrapping_add(Self::GAMMA))),
        }
    }

    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(Self::GAMMA);
        mix64(self.state)
    }

    /// Uniform in [0, 1), 53 random bits.
    fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// SplitMix64's output finaliser (a bijection of u64 with good avalanche).
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A_spec(nv) = ∫ f_spec(N, V, s)·(N·s) dω_s of one material, at [`ALBEDO_KNOTS`] knots evenly
/// spaced in nv over [0, 1], each from `specular_albedo` with [`ALBEDO_STEPS`]² midpoints, read
/// with linear interpolation.
///
/// Accuracy, measured against `specular_albedo` at 2048 × 1024 steps (itself converged to
/// 1.5e-5 against 4096 × 2048) at all 256 knots and the 255 midpoints between them, worst
/// channel: rough presets (m = 0.2) worst 1.7e-3 relative at nv = 2/255 (a knot, so the 128²
/// quadrature itself at grazing view), ≤ 1.9e-4 for nv ≥ 0.1, mean 1.0e-4; smooth presets
/// (m = 0.05) worst 3.3e-4 at nv ≈ 0.01, ≤ 1.8e-4 for nv ≥ 0.1, mean 4.4e-5. Far below the
/// Monte-Carlo noise the path tracer is used with.
struct AlbedoTable {
    knots: Vec<[f64; 3]>,
}

impl AlbedoTable {
    fn new(brdf: &BrdfParams, fresnel: &FresnelTable, threads: usize) -> Self {
        let last = (ALBEDO_KNOTS - 1) as f64;
        let knots = parallel_map(ALBEDO_KNOTS, threads, |i| {
            specular_albedo(brdf, fresnel, i as f64 / last, ALBEDO_STEPS, ALBEDO_STEPS)
        });
        Self { knots }
    }

    fn eval(&self, nv: f64) -> [f64; 3] {
        let x = nv.clamp(0.0, 1.0) * (self.knots.len() - 1) as f64;
        let i = (x.floor() as usize).min(self.knots.len() - 2);
        let t = x - i as f64;
        let (lo, hi) = (self.knots[i], self.knots[i + 1]);
        std::array::from_fn(|c| lo[c] + (hi[c] - lo[c]) * t)
    }
}

/// A point where a ray met an object.
struct SurfacePoint {
    object: usize,
    /// The interpolated point in f32, where secondary rays leave from (after the offset).
    point: Vec3,
    /// Unit shading normal (interpolated vertex normals), `None` where they cancel.
    normal: Option<DVec3>,
    /// Unit geometric normal of the triangle (winding side), for the ray-origin offset.
    geometric_normal: Vec3,
}

impl SurfacePoint {
    fn position(&self) -> DVec3 {
        self.point.as_dvec3()
    }

    /// Where a ray towards `dir` leaves: the point pushed off the triangle's plane to `dir`'s side.
    fn ray_origin(&self, dir: Vec3) -> Vec3 {
        let side = if self.geometric_normal.dot(dir) < 0.0 {
            -self.geometric_normal
        } else {
            self.geometric_normal
        };
        offset_ray_origin(self.point, side)
    }
}

/// The scene prepared for tracing: the BVH and the per-material albedo tables.
struct Tracer<'a> {
    objects: &'a [TracedObject<'a>],
    camera: &'a Camera,
    lights: &'a [Light],
    /// The constant environment's c; zero under a map.
    environment: DVec3,
    /// The map and its sampler; `None` under a constant environment (or a map with no light).
    map: Option<MapSampler<'a>>,
    bounces: u32,
    bvh: SceneBvh,
    /// `tables[table_of[k]]` is object k's A_spec; empty when the environment is black (then
    /// L_env_model is 0 and no table is needed).
    tables: Vec<AlbedoTable>,
    table_of: Vec<usize>,
}

impl<'a> Tracer<'a> {
    fn new(scene: &PathScene<'a>, bounces: u32, threads: usize) -> Self {
        let meshes: Vec<(&[[f32; 3]], &[u32])> = scene
            .objects
            .iter()
            .map(|o| (o.mesh.positions.as_slice(), o.mesh.indices.as_slice()))
            .collect();
        let (environment, map) = match scene.environment {
            PathEnvironment::Constant(c) => (DVec3::from_array(c), None),
            PathEnvironment::Map { image, light } => (DVec3::ZERO, MapSampler::new(image, light)),
        };
        let mut tables = Vec::new();
        let mut table_of = Vec::with_capacity(scene.objects.len());
        if environment != DVec3::ZERO {
            // Objects with equal materials share one table: building it is most of the set-up.
            let mut materials: Vec<(&BrdfParams, &FresnelTable)> = Vec::new();
            for object in scene.objects {
                let index = materials
                    .iter()
                    .position(|&(b, f)| b == object.brdf && f == object.fresnel)
                    .unwrap_or_else(|| {
                        materials.push((object.brdf, object.fresnel));
                        tables.push(AlbedoTable::new(object.brdf, object.fresnel, threads));
                        materials.len() - 1
                    });
                table_of.push(index);
            }
        }
        Self {
            objects: scene.objects,
            camera: scene.camera,
            lights: scene.lights,
            environment,
            map,
            bounces,
            bvh: SceneBvh::new(&meshes),
            tables,
            table_of,
        }
    }

    /// The statistics of `paths` paths through the centre of pixel (x, y), or `None` where the
    /// primary ray meets nothing.
    fn pixel(
        &self,
        x: u32,
        y: u32,
        (width, height): (u32, u32),
        paths: u32,
        seed: u64,
    ) -> Option<PixelStats> {
        let dir = self
            .camera
            .primary_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, width, height);
        let hit =
            self.bvh
                .intersect(self.camera.eye.as_vec3(), dir.as_vec3(), 0.0, f32::INFINITY)?;
        let first = self.surface_point(&hit);
        let mut rng = SplitMix64::for_pixel(seed, u64::from(y) * u64::from(width) + u64::from(x));
        let mut stats = PixelStats::new();
        for _ in 0..paths {
            stats.add(self.path(&first, -dir, &mut rng));
        }
        Some(stats)
    }

    /// One path's estimate of L(x, V, 1), the recursion of the module doc unrolled: `throughput`
    /// is the product of the f_r·(N·s)/pdf(s) weights of the directions drawn so far.
    fn path(&self, first: &SurfacePoint, view: DVec3, rng: &mut SplitMix64) -> DVec3 {
        let mut radiance = DVec3::ZERO;
        let mut throughput = DVec3::ONE;
        let mut next: Option<SurfacePoint> = None;
        let mut v = view;
        for depth in 1..=self.bounces + 1 {
            let surface = next.as_ref().unwrap_or(first);
            let Some(n) = surface.normal else { break };
            let nv = n.dot(v);
            // The back of a surface: the BRDF is 0 (SPEC §2), so nothing is reflected.
            if !positive(nv) {
                break;
            }
            radiance += throughput * self.direct_light(surface, n, v);
            let last = depth == self.bounces + 1;
            if let Some(map) = &self.map {
                radiance += throughput * self.map_draw(map, surface, (n, v), !last, rng);
            }
            if last && self.map.is_none() {
                radiance += throughput * self.environment_model(surface.object, nv);
                break;
            }
            let Some((s, weight, pdf)) = self.sample_direction(surface.object, n, v, rng) else {
                break;
            };
            throughput *= weight;
            let dir = s.as_vec3();
            let hit = match last {
                // The environment model: the whole map, nothing in the way.
                true => None,
                false => self
                    .bvh
                    .intersect(surface.ray_origin(dir), dir, 0.0, f32::INFINITY),
            };
            match hit {
                Some(hit) => {
                    next = Some(self.surface_point(&hit));
                    v = -s;
                }
                None => {
                    radiance += throughput * self.escaped(s, pdf);
                    break;
                }
            }
        }
        radiance
    }

    /// What a BRDF-drawn direction `s` (drawn with density `pdf`) that meets nothing brings, per
    /// unit throughput: c, or L(s) weighted against the map's own draw of s (balance heuristic).
    fn escaped(&self, s: DVec3, pdf: f64) -> DVec3 {
        match &self.map {
            None => self.environment,
            Some(map) => map.radiance(s) * (pdf / (pdf + map.pdf(s))),
        }
    }

    /// The map's draw at a surface point: a direction s from the map, and
    /// f_r·L(s)·(N·s)/(p_map(s) + p_brdf(s)), its share of the two draws (balance heuristic);
    /// 0 where s is below the surface or, when `shadowed`, an object is in the way.
    fn map_draw(
        &self,
        map: &MapSampler,
        surface: &SurfacePoint,
        (n, v): (DVec3, DVec3),
        shadowed: bool,
        rng: &mut SplitMix64,
    ) -> DVec3 {
        let s = map.sample([rng.next_f64(), rng.next_f64(), rng.next_f64()]);
        let ns = n.dot(s);
        if !positive(ns) {
            return DVec3::ZERO;
        }
        let dir = s.as_vec3();
        if shadowed
            && self
                .bvh
                .occluded(surface.ray_origin(dir), dir, 0.0, RAY_FAR)
        {
            return DVec3::ZERO;
        }
        let object = &self.objects[surface.object];
        let pdf = map.pdf(s) + mixture_pdf(n, v, s, object.brdf.beckmann_m);
        if !positive(pdf) {
            return DVec3::ZERO;
        }
        let f_r = DVec3::from(lacquer_brdf(object.brdf, object.fresnel, n, v, s));
        f_r * map.radiance(s) * (ns / pdf)
    }

    /// Position and normals at a BVH hit: barycentric interpolation of the triangle's vertices
    /// (vertex 0 weighs 1 - u - v) and of its vertex normals.
    fn surface_point(&self, hit: &BvhHit) -> SurfacePoint {
        let object = hit.object as usize;
        let mesh = self.objects[object].mesh;
        let [(p0, n0), (p1, n1), (p2, n2)] = [0, 1, 2].map(|k| {
            let index = mesh.indices[3 * hit.triangle as usize + k] as usize;
            (
                Vec3::from(mesh.positions[index]),
                Vec3::from(mesh.normals[index]).as_dvec3(),
            )
        });
        let [u, v] = hit.barycentrics;
        let w = 1.0 - u - v;
        let point = w * p0 + u * p1 + v * p2;
        let (ud, vd) = (f64::from(u), f64::from(v));
        let normal = ((1.0 - ud - vd) * n0 + ud * n1 + vd * n2).try_normalize();
        // A degenerate triangle cannot orient the offset; its shading normal stands in.
        let geometric_normal = (p1 - p0)
            .cross(p2 - p0)
            .try_normalize()
            .or_else(|| normal.map(|n| n.as_vec3()))
            .unwrap_or(Vec3::Y);
        SurfacePoint {
            object,
            point,
            normal,
            geometric_normal,
        }
    }

    /// Σ over the lights of f_r·E·(N·L)·vis at `surface` seen from `v`.
    fn direct_light(&self, surface: &SurfacePoint, n: DVec3, v: DVec3) -> DVec3 {
        let object = &self.objects[surface.object];
        let p = surface.position();
        let mut radiance = DVec3::ZERO;
        for light in self.lights {
            let Some((l, irradiance)) = light.incident_at(p) else {
                continue;
            };
            let nl = n.dot(l);
            if !positive(nl) || !self.light_visible(surface, light) {
                continue;
            }
            let f_r = DVec3::from(lacquer_brdf(object.brdf, object.fresnel, n, v, l));
            radiance += f_r * irradiance * nl;
        }
        radiance
    }

    /// vis(x, L) of SPEC §6: nothing between the offset origin and the light (up to its position
    /// for a point light, up to [`RAY_FAR`] for a directional one).
    fn light_visible(&self, surface: &SurfacePoint, light: &Light) -> bool {
        match *light {
            Light::Directional { to_light, .. } => {
                let dir = to_light.normalize_or_zero().as_vec3();
                !self
                    .bvh
                    .occluded(surface.ray_origin(dir), dir, 0.0, RAY_FAR)
            }
            Light::Point { position, .. } => {
                let position = position.as_vec3();
                let origin = surface.ray_origin(position - surface.point);
                let to_light = position - origin;
                let distance = to_light.length();
                !positive(f64::from(distance))
                    || !self
                        .bvh
                        .occluded(origin, to_light / distance, 0.0, distance)
            }
        }
    }

    /// L_env_model of SPEC §4's `brdf` model under the constant environment c, in closed form:
    /// c·A_spec(nv) + f_diff(nv)·π·c.
    fn environment_model(&self, object: usize, nv: f64) -> DVec3 {
        if self.environment == DVec3::ZERO {
            return DVec3::ZERO;
        }
        let specular = DVec3::from(self.tables[self.table_of[object]].eval(nv));
        let diffuse = DVec3::from(view_dependent_diffuse(self.objects[object].brdf, nv));
        self.environment * (specular + PI * diffuse)
    }

    /// One direction s from the mixture sampler, its weight f_r(N, V, s)·(N·s)/pdf(s) and
    /// pdf(s), or `None` where the weight is 0 (s below the surface, or outside both lobes).
    fn sample_direction(
        &self,
        object: usize,
        n: DVec3,
        v: DVec3,
        rng: &mut SplitMix64,
    ) -> Option<(DVec3, DVec3, f64)> {
        let object = &self.objects[object];
        let m = object.brdf.beckmann_m;
        let s = sample_mixture(n, v, m, [rng.next_f64(), rng.next_f64(), rng.next_f64()])?;
        let ns = n.dot(s);
        if !positive(ns) {
            return None;
        }
        let pdf = mixture_pdf(n, v, s, m);
        if !positive(pdf) {
            return None;
        }
        let f_r = DVec3::from(lacquer_brdf(object.brdf, object.fresnel, n, v, s));
        Some((s, f_r * (ns / pdf), pdf))
    }
}

/// A direction from the mixture: with probability [`COSINE_WEIGHT`] (decided by `u[0]`) from the
/// cosine lobe about `n`, else V mirrored about a Beckmann half vector. A half vector facing away
/// from V (V·H < 0) still mirrors V to a unit direction, always below the surface
/// (N·s = 2(V·H)(N·H) − N·V < 0) where the BRDF is 0; keeping it rather than rejecting it is what
/// makes [`mixture_pdf`] integrate to 1 over the sphere. `None` only for a degenerate mirror.
fn sample_mixture(n: DVec3, v: DVec3, m: f64, u: [f64; 3]) -> Option<DVec3> {
    let (t, b) = n.any_orthonormal_pair();
    let to_world = |local: DVec3| local.x * t + local.y * b + local.z * n;
    if u[0] < COSINE_WEIGHT {
        return Some(to_world(cosine_local(u[1], u[2])));
    }
    let h = to_world(beckmann_half_local(m, u[1], u[2]));
    (2.0 * v.dot(h) * h - v).try_normalize()
}

/// Cosine-weighted direction about +Z (Malley's method): pdf = cos θ / π.
fn cosine_local(u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = TAU * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// Beckmann half vector about +Z: tan²θ_h = -m²·ln(1 - u1), φ = 2π·u2, which draws h with
/// pdf D(h)·(n·h) (the cumulative of D·cos θ_h in tan²θ_h is 1 - exp(-tan²θ_h/m²)).
fn beckmann_half_local(m: f64, u1: f64, u2: f64) -> DVec3 {
    let tan2 = -m * m * (-u1).ln_1p();
    let cos = 1.0 / (1.0 + tan2).sqrt();
    let sin = (tan2 / (1.0 + tan2)).sqrt();
    let phi = TAU * u2;
    DVec3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// The pdf (per steradian) with which [`sample_mixture`] draws the unit direction `s`:
/// COSINE_WEIGHT·max(N·s, 0)/π + (1 - COSINE_WEIGHT)·D(h)·(n·h)/(4·|v·h|), with h = ±(V + s)/|V + s|
/// taken on N's side (the one of the two that mirrors V onto s and that the Beckmann sampler can
/// draw; dω_s = 4·|v·h|·dω_h). Defined on the whole sphere so that tests can check it
/// integrates to 1; the renderer only evaluates it above the surface, where h = (V + s)/|V + s|.
fn mixture_pdf(n: DVec3, v: DVec3, s: DVec3, m: f64) -> f64 {
    let cosine = n.dot(s).max(0.0) / PI;
    let beckmann = match (v + s).try_normalize() {
        Some(h) => {
            let h = if n.dot(h) < 0.0 { -h } else { h };
            let vh = v.dot(h).abs();
            if vh > 0.0 {
                beckmann_d(n, h, m) * n.dot(h) / (4.0 * vh)
            } else {
                0.0
            }
        }
        None => 0.0,
    };
    COSINE_WEIGHT * cosine + (1.0 - COSINE_WEIGHT) * beckmann
}

/// x > 0, and false for NaN: the guards below are written with it so that a NaN (a degenerate
/// normal or direction) ends a path with 0 rather than spreading into the image.
fn positive(x: f64) -> bool {
    x > 0.0
}

/// The normalised Beckmann distribution D = exp(-tan²θ_h/m²)/(π·m²·cos⁴θ_h), for h on n's side;
/// tan²θ_h is formed as |n×h|²/(n·h)², which stays accurate at the peak of a sharp lobe.
fn beckmann_d(n: DVec3, h: DVec3, m: f64) -> f64 {
    let nh = n.dot(h);
    if !positive(nh) {
        return 0.0;
    }
    let nh2 = nh * nh;
    let m2 = m * m;
    let lobe = (-n.cross(h).length_squared() / (m2 * nh2)).exp();
    if lobe == 0.0 {
        return 0.0;
    }
    lobe / (PI * m2 * nh2 * nh2)
}

#[cfg(test)]
mod tests {
    use glam::DMat4;

    use super::*;
    use crate::model::LacquerMaterial;
    use crate::oracle::shadows::TracedScene;
    use crate::raster::mesh::board;
    use crate::raster::mesh_io::transform_mesh;
    use crate::raster::Mesh;

    /// A material's BRDF and Fresnel table.
    fn material(name: &str) -> (BrdfParams, FresnelTable) {
        let m = LacquerMaterial::preset(name).unwrap();
        (m.brdf_params().unwrap(), m.fresnel_table().unwrap())
    }

    fn small_camera() -> Camera {
        Camera {
            eye: DVec3::new(0.0, 2.0, 2.5),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_deg: 40.0,
        }
    }

    /// A unit view vector at `nv` to `n`.
    fn view_at(n: DVec3, nv: f64) -> DVec3 {
        let (t, _) = n.any_orthonormal_pair();
        nv * n + (1.0 - nv * nv).sqrt() * t
    }

    /// The expected unoccluded environment term c·A_spec(nv) + f_diff(nv)·π·c, with A_spec from
    /// a finer quadrature than the table's (so the table is under test too).
    fn closed_form(brdf: &BrdfParams, fresnel: &FresnelTable, nv: f64, c: [f64; 3]) -> [f64; 3] {
        let a = specular_albedo(brdf, fresnel, nv, 256, 256);
        let d = view_dependent_diffuse(brdf, nv);
        std::array::from_fn(|k| c[k] * (a[k] + PI * d[k]))
    }

    /// The mixture pdf integrates to 1 over the sphere (to 4e-8 here, hence 1e-6), and the
    /// sampler draws from it: the sample mean of max(N·s, 0)/pdf(s) is ∫ cos dω = π.
    ///
    /// The quadrature is a midpoint rule in polar coordinates about -V: there (s → -V) the
    /// Beckmann part of the pdf grows like 1/∠(s, -V) (a whole circle of half vectors ⊥ V mirrors
    /// V onto -V), which the sin θ of those coordinates cancels; everywhere else the integrand is
    /// smooth and the grid resolves even the m = 0.05 lobe by tens of cells.
    #[test]
    fn mixture_pdf_integrates_to_one_and_matches_the_sampler() {
        let n = DVec3::new(0.2, 0.9, -0.3).normalize();
        for m in [0.05, 0.2, 0.6] {
            for nv in [0.95, 0.5, 0.15] {
                let v = view_at(n, nv);
                let (a, b) = v.any_orthonormal_pair();
                let (steps_theta, steps_phi) = (4096, 1024);
                let cell = (PI / f64::from(steps_theta)) * (TAU / f64::from(steps_phi));
                let mut total = 0.0;
                for i in 0..steps_theta {
                    let theta = PI * (f64::from(i) + 0.5) / f64::from(steps_theta);
                    let (sin_t, cos_t) = theta.sin_cos();
                    for j in 0..steps_phi {
                        let phi = TAU * (f64::from(j) + 0.5) / f64::from(steps_phi);
                        let s = -cos_t * v + sin_t * (phi.cos() * a + phi.sin() * b);
                        total += mixture_pdf(n, v, s, m) * sin_t * cell;
                    }
                }
                assert!(
                    (total - 1.0).abs() < 1e-6,
                    "m {m}, nv {nv}: ∫ pdf = {total}"
                );

                let mut rng = SplitMix64::for_pixel(7, 0);
                let count = 200_000;
                let (mut sum, mut sum2) = (0.0, 0.0);
                for _ in 0..count {
                    let u = [rng.next_f64(), rng.next_f64(), rng.next_f64()];
                    let Some(s) = sample_mixture(n, v, m, u) else {
                        continue;
                    };
                    let ns = n.dot(s);
                    if ns > 0.0 {
                        let x = ns / mixture_pdf(n, v, s, m);
                        sum += x;
                        sum2 += x * x;
                    }
                }
                let mean = sum / f64::from(count);
                let se = ((sum2 / f64::from(count) - mean * mean) / f64::from(count)).sqrt();
                assert!(
                    (mean - PI).abs() < 4.0 * se + 1e-3,
                    "m {m}, nv {nv}: E[cos/pdf] = {mean} ± {se}"
                );
            }
        }
    }

    /// White furnace of the mixture sampler: E[f_r·cos/pdf] = A_spec(nv) + f_diff·π, the
    /// albedo of the whole BRDF, within 1 % (and within 4 standard errors + 0.2 %).
    #[test]
    fn white_furnace_of_the_sampler_gives_the_albedo() {
        let n = DVec3::new(-0.3, 0.8, 0.4).normalize();
        for name in ["smooth-black", "rough-red"] {
            let (brdf, fresnel) = material(name);
            for nv in [0.9, 0.5, 0.2] {
                let v = view_at(n, nv);
                let want = closed_form(&brdf, &fresnel, nv, [1.0; 3]);
                let mut rng = SplitMix64::for_pixel(11, 3);
                let mut stats = PixelStats::new();
                for _ in 0..200_000 {
                    let u = [rng.next_f64(), rng.next_f64(), rng.next_f64()];
                    let value = match sample_mixture(n, v, brdf.beckmann_m, u) {
                        Some(s) if n.dot(s) > 0.0 => {
                            let f = DVec3::from(lacquer_brdf(&brdf, &fresnel, n, v, s));
                            f * n.dot(s) / mixture_pdf(n, v, s, brdf.beckmann_m)
                        }
                        _ => DVec3::ZERO,
                    };
                    stats.add(value);
                }
                let se = stats.std_error();
                for c in 0..3 {
                    let (got, want) = (stats.mean[c], want[c]);
                    let diff = (got - want).abs();
                    assert!(
                        diff < 0.01 * want && diff < 4.0 * se + 2e-3 * want,
                        "{name}, nv {nv}, channel {c}: {got} ± {se} vs {want}"
                    );
                }
            }
        }
    }

    /// How a lone board's path-traced image must meet what each pixel estimates.
    struct LoneBoard<'a> {
        name: &'a str,
        environment: PathEnvironment<'a>,
        bounces: u32,
        paths: u32,
        seed: u64,
        size: u32,
        /// The least number of pixels the board must cover.
        min_covered: u32,
        /// The bound per pixel and channel beyond 4 standard errors, relative.
        pixel_slack: f64,
        /// The bound on the mean relative error beyond 4 of its standard errors.
        mean_slack: f64,
    }

    /// Renders a lone board (`material`, seen by `small_camera`) under `case.environment` and
    /// checks each covered pixel against `want(n, v)` (N = +Y, V towards the camera), and the
    /// mean relative error over all pixels and channels, which shows a bias the per-pixel test
    /// cannot.
    fn check_lone_board(case: LoneBoard, want: impl Fn(DVec3, DVec3) -> [f64; 3]) {
        let LoneBoard { name, size, .. } = case;
        let camera = small_camera();
        let mesh = board();
        let (brdf, fresnel) = material(name);
        let objects = [TracedObject {
            mesh: &mesh,
            brdf: &brdf,
            fresnel: &fresnel,
        }];
        let scene = PathScene {
            objects: &objects,
            camera: &camera,
            lights: &[],
            environment: case.environment,
        };
        let image = render(&scene, (size, size), case.bounces, case.paths, case.seed);
        let (mut covered, mut relative_sum, mut relative_variance_sum) = (0, 0.0, 0.0);
        for y in 0..size {
            for x in 0..size {
                let pixel = image.mean.get(x, y);
                if pixel[3] == 0.0 {
                    continue;
                }
                covered += 1;
                let dir = camera.primary_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, size, size);
                let want = want(DVec3::Y, -dir);
                let se = image.std_error[(y * size + x) as usize];
                for (k, want) in want.into_iter().enumerate() {
                    let got = f64::from(pixel[k]);
                    relative_sum += (got - want) / want;
                    relative_variance_sum += (se / want).powi(2);
                    assert!(
                        (got - want).abs() <= 4.0 * se + case.pixel_slack * want,
                        "{name} ({x}, {y}) channel {k}: {got} ± {se} vs {want}"
                    );
                }
            }
        }
        assert!(
            covered > case.min_covered,
            "the board covers {covered} pixels"
        );
        let values = f64::from(3 * covered);
        let (mean, se) = (relative_sum / values, relative_variance_sum.sqrt() / values);
        assert!(
            mean.abs() <= 4.0 * se + case.mean_slack,
            "{name}: mean relative error {mean} ± {se}"
        );
    }

    /// A lone board under a constant environment with B = 1: every sampled direction escapes,
    /// so each pixel estimates c·A_spec(nv) + f_diff·π·c, which it must match within 4 standard
    /// errors + 0.5 %, and so must the mean over the pixels (within 4 of its standard errors +
    /// 0.1 %: one pixel's error is ~3 % at 1024 paths, the mean's ~0.1 %; measured -0.07 %
    /// smooth-black, +0.04 % rough-red). This tests the sampler, its pdf and the table together.
    #[test]
    fn lone_board_reproduces_the_closed_form_environment() {
        let c = [0.8, 1.0, 1.3];
        for name in ["smooth-black", "rough-red"] {
            let (brdf, fresnel) = material(name);
            let case = LoneBoard {
                name,
                environment: PathEnvironment::Constant(c),
                bounces: 1,
                paths: 1024,
                seed: 5,
                size: 16,
                min_covered: 64,
                pixel_slack: 0.005,
                mean_slack: 1e-3,
            };
            check_lone_board(case, |n, v| closed_form(&brdf, &fresnel, n.dot(v), c));
        }
    }

    /// A lone board under a real map's kind of light (a dim sky and a small disc 300× brighter,
    /// turned and scaled) with B = 0 and B = 1: every direction escapes, so each pixel estimates
    /// SPEC §4's `brdf` model, f_diff(nv)·E_irr(N) + ∫ f_spec·L·(N·s) dω, here from the
    /// brute-force definitions over the map's pixels. Per pixel within 4 standard errors + 1 %
    /// (the definitions read each pixel at its centre, or 4 × 4 cells for the specular term, on
    /// a 2.8° grid); the mean over pixels and channels within 4 of its standard errors + 0.3 %.
    #[test]
    fn lone_board_under_a_map_reproduces_the_brdf_model() {
        use crate::environment::brdf_definition::specular_integral_definition;
        use crate::environment::cube::world_to_environment;
        use crate::environment::definition::irradiance_definition;

        let sun = DVec3::new(-0.3, 0.5, 0.8).normalize();
        let image = Equirect::from_fn(128, 64, |s| {
            let sky = 0.3 + 0.2 * s.y.max(0.0);
            let disc = if s.dot(sun) > 0.995 { 100.0 } else { 0.0 };
            [
                (sky + disc) as f32,
                (sky + 0.9 * disc) as f32,
                (1.2 * sky) as f32,
            ]
        });
        let light = EnvironmentLight {
            intensity: 0.8,
            rotation_deg: 25.0,
        };
        for (name, bounces) in [("smooth-black", 0), ("rough-red", 1)] {
            let (brdf, fresnel) = material(name);
            let case = LoneBoard {
                name,
                environment: PathEnvironment::Map {
                    image: &image,
                    light,
                },
                bounces,
                paths: 2048,
                seed: 3,
                size: 12,
                min_covered: 32,
                pixel_slack: 0.01,
                mean_slack: 3e-3,
            };
            check_lone_board(case, |n, v| {
                let local = world_to_environment(n, light.rotation_deg);
                let irradiance = irradiance_definition(&image, local);
                let diffuse = view_dependent_diffuse(&brdf, n.dot(v));
                let specular =
                    specular_integral_definition(&image, light, &brdf, &fresnel, n, v, 4);
                std::array::from_fn(|k| specular[k] + diffuse[k] * irradiance[k] * light.intensity)
            });
        }
    }

    /// A 0.6 × 0.6 board floating at y = 0.5 over the big one, to cast a shadow on it. All
    /// flat, so the shading pass's CPU twin (which lifts ray origins onto the smooth surface)
    /// leaves from the same points as the path tracer.
    fn two_boards() -> (Mesh, Mesh) {
        let floating = transform_mesh(
            &board(),
            DMat4::from_translation(DVec3::new(0.1, 0.5, 0.2))
                * DMat4::from_scale(DVec3::splat(0.3)),
        );
        (board(), floating)
    }

    /// B = 0 is exact, with no noise: lights with visibility (against the shading pass's CPU
    /// twin) plus the closed-form environment model (against a finer quadrature, on the big
    /// board where nv is known analytically), and the two add.
    #[test]
    fn no_bounce_is_lights_with_visibility_plus_the_environment_model() {
        let camera = small_camera();
        let size = 16;
        let (big, floating) = two_boards();
        let (brdf, fresnel) = material("rough-red");
        let objects = [&big, &floating].map(|mesh| TracedObject {
            mesh,
            brdf: &brdf,
            fresnel: &fresnel,
        });
        let lights = [
            Light::Directional {
                to_light: DVec3::new(-0.2, 1.0, -0.1).normalize(),
                irradiance: DVec3::new(3.0, 2.5, 2.0),
            },
            Light::Point {
                position: DVec3::new(0.5, 1.5, 0.8),
                intensity: DVec3::splat(2.0),
            },
        ];
        let c = [0.5, 0.6, 0.7];
        let scene = |lights, environment| PathScene {
            objects: &objects,
            camera: &camera,
            lights,
            environment: PathEnvironment::Constant(environment),
        };
        let both = render(&scene(&lights, c), (size, size), 0, 64, 1);
        let lit = render(&scene(&lights, [0.0; 3]), (size, size), 0, 64, 1);
        let env = render(&scene(&[], c), (size, size), 0, 64, 1);
        assert!(both.std_error.iter().all(|&e| e == 0.0));

        let twin = TracedScene::new(&objects);
        let shadowed = twin.render(&camera, &lights, (size, size), true);
        let unshadowed = twin.render(&camera, &lights, (size, size), false);
        let (mut in_shadow, mut on_big) = (0, 0);
        for y in 0..size {
            for x in 0..size {
                let [b, l, e, t] =
                    [&both.mean, &lit.mean, &env.mean, &shadowed].map(|i| i.get(x, y));
                assert_eq!(b[3], t[3], "coverage at ({x}, {y})");
                for k in 0..3 {
                    let tolerance = 1e-5 * b[k].abs().max(1e-3);
                    assert!(
                        (l[k] - t[k]).abs() <= tolerance,
                        "({x}, {y}): {l:?} vs {t:?}"
                    );
                    assert!((b[k] - l[k] - e[k]).abs() <= tolerance, "({x}, {y})");
                }
                if l[0] < 0.9 * unshadowed.get(x, y)[0] {
                    in_shadow += 1;
                }
                // On the big board (the plane y = 0, where nv is -dir.y) the environment term is
                // the closed form.
                let dir = camera.primary_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, size, size);
                let hit =
                    twin.bvh()
                        .intersect(camera.eye.as_vec3(), dir.as_vec3(), 0.0, f32::INFINITY);
                if hit.is_some_and(|h| h.object == 0) {
                    on_big += 1;
                    let want = closed_form(&brdf, &fresnel, -dir.y, c);
                    for k in 0..3 {
                        let rel = (f64::from(e[k]) - want[k]).abs() / want[k];
                        assert!(rel < 1e-3, "({x}, {y}) channel {k}: {e:?} vs {want:?}");
                    }
                }
            }
        }
        assert!(on_big > 64, "{on_big} pixels on the big board");
        assert!(in_shadow > 0, "the floating board casts no shadow in view");
    }

    /// The same seed gives the same image bit for bit, on any number of threads; another seed
    /// gives another image.
    #[test]
    fn images_are_deterministic_per_seed() {
        let camera = small_camera();
        let (big, floating) = two_boards();
        let (brdf, fresnel) = material("smooth-black");
        let objects = [&big, &floating].map(|mesh| TracedObject {
            mesh,
            brdf: &brdf,
            fresnel: &fresnel,
        });
        let lights = [Light::Directional {
            to_light: DVec3::new(0.3, 1.0, 0.2).normalize(),
            irradiance: DVec3::splat(2.0),
        }];
        let scene = PathScene {
            objects: &objects,
            camera: &camera,
            lights: &lights,
            environment: PathEnvironment::Constant([1.0; 3]),
        };
        let one = render_on_threads(&scene, (16, 16), 2, 8, 42, 1);
        let many = render_on_threads(&scene, (16, 16), 2, 8, 42, 5);
        let again = render(&scene, (16, 16), 2, 8, 42);
        let other = render(&scene, (16, 16), 2, 8, 43);
        assert_eq!(one.mean, many.mean);
        assert_eq!(one.std_error, many.std_error);
        assert_eq!(one.mean, again.mean);
        assert_ne!(one.mean, other.mean);
    }

    /// The A_spec table against `specular_albedo` at 1024 × 512 steps, at knots and midpoints
    /// between them: all of the grazing end (where the table is least accurate, see
    /// [`AlbedoTable`]) and every 17th knot beyond. Bounds: the measured worst (1.7e-3 below
    /// nv = 0.1, 1.9e-4 above) with some room.
    #[test]
    fn albedo_table_matches_a_fine_quadrature() {
        for name in ["smooth-black", "rough-red"] {
            let (brdf, fresnel) = material(name);
            let table = AlbedoTable::new(&brdf, &fresnel, 8);
            let last = (ALBEDO_KNOTS - 1) as f64;
            let knots = (0..8).chain((8..ALBEDO_KNOTS - 1).step_by(17));
            for i in knots {
                for nv in [i as f64 / last, (i as f64 + 0.5) / last] {
                    let want = specular_albedo(&brdf, &fresnel, nv, 1024, 512);
                    let got = table.eval(nv);
                    let bound = if nv < 0.1 { 2.5e-3 } else { 3e-4 };
                    for c in 0..3 {
                        let rel = (got[c] - want[c]).abs() / want[c];
                        assert!(rel < bound, "{name}, nv {nv}: {got:?} vs {want:?}");
                    }
                }
            }
            // The last knot, nv = 1 exactly.
            let want = specular_albedo(&brdf, &fresnel, 1.0, 1024, 512);
            assert!((table.eval(1.0)[0] - want[0]).abs() < 3e-4 * want[0]);
        }
    }
}
