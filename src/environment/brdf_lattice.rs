//! SPEC §4's `brdf` environment model for a narrow lobe (m up to `LATTICE_M_HI`, the smooth
//! preset): a lattice of lookups along the plane of incidence ([`specular_lattice`]) and its
//! constants. The CPU twin of brdf_environment.glsl's `specular_lattice` and `lattice_by_node`,
//! formula by formula; the other quadratures, the lookups and the sums the lattice shares with
//! them are in `brdf_quadrature.rs`.

use glam::DVec3;

use super::brdf_quadrature::{
    cube_bilinear, incidence, lattice_taper, layered_radiance, lookup, smoothstep01, Incidence,
    LookupSums,
};
use super::image::PrefilteredEnvironment;
use super::sharp_source::{SharpSource, SHARP_NODES};
use crate::model::{BrdfParams, FresnelTable};

/// The plane-of-incidence lattice (`specular_lattice`): the share of the lobe's width across the
/// plane that the lookups' blur supplies, node spacing in units of the blur, reach in standard
/// deviations of the nodes' distribution, most nodes on each side of the mirror direction.
/// Measured in BENCHMARKS.md ("The `brdf` environment model"); packed into `Frame::env_lattice`
/// and `env_lattice_share` for the shaders.
/// t = 1 keeps the default scene within the issue's ≤ 1.5× `paper`; t = 0.93, spacing 1.7, reach
/// 3.0 is a third more accurate on a sphere and costs ~1.6× (BENCHMARKS.md). At most 24 nodes a
/// side: with fewer, the step is held at reach/`LATTICE_MAX_HALF` below nv = 3/(2·max), each
/// lookup blurred that much wider than the lobe across the plane, and at 12 the studio's point
/// at nv = 0.054 read +55 % at m = 0.05 (+7 % at 24; the 112 points' mean 1.33 → 0.90 %). Only
/// grazing pixels pay (BENCHMARKS.md, "The series continued below β_min"). The reach was 2.5 σ: the
/// taper then starts at 2σ, and the ratio estimator gives the lobe's tails beyond it the core's
/// radiance. With lookups at exactly the blur they ask for (a brute-force Gaussian over the map's
/// pixels, an experiment), the courtyard's 112 points at m = 0.02 were 1.64 % off on average at
/// reach 2.5, 0.99 % at 3.0, 0.81 % at 3.5; with the layers (and their blend in variance,
/// [`layered_radiance`]) 1.05 % at 3.0 and 0.99 % at 3.5, but 3.5 took the default scene's `brdf`
/// draw from 1.67 to 1.84× `paper` (median of three interleaved runs), 3.0 to 1.73×: near
/// face-on the nodes 2 steps out stay outside 3σ (BENCHMARKS.md, "Lookups at the blur they ask
/// for"). The reach then went to 4 σ (2026-12-06) with the layers blurred net of their read
/// (`params::BRDF_BLUR_NET_OF_READ`): a dark point beside a bright patch 4–6 σ away is all the
/// lobe's tails. The 112 points at m = 0.05 went from 1.10 / 11.8 % (mean / p99, courtyard, the
/// layers net of their read at 3 σ) to 0.81 / 4.5 %, at 3.5 σ 0.85 / 9.2 %; the default scene's
/// `brdf` draw from 1.39–1.44 to 1.49–1.51× `paper` (three interleaved rounds; BENCHMARKS.md,
/// "Layers net of their read").
pub const LATTICE_BLUR_SHARE: f64 = 1.0;
pub const LATTICE_SPACING: f64 = 2.0;
pub const LATTICE_REACH: f64 = 4.0;
pub const LATTICE_MAX_HALF: u32 = 24;
/// The widest node step, in standard deviations σ_p of the nodes' distribution. Towards normal
/// incidence the blur's step (2·nv·σ) outgrows σ_p, and the ±1 nodes fell outside the reach: one
/// lookup, and the in-plane variance σ_p² the blur does not supply was lost (dark points beside
/// the courtyard's bright sky read −25 %, its board at 60° was 9.9 % off at m = 0.05). At √3·σ_p
/// the three nodes carried Gaussian weights close to the 3-point Gauss–Hermite rule's (1/6, 2/3,
/// 1/6), which has the variance and the fourth moment of the Gaussian: that board 1.4 %. Since
/// the reach went to 4σ_p the ±2 nodes are inside it too, and at √3 (3.46σ_p) they fell in the
/// taper, which starts at 3.2σ_p and took a quarter of their weight: the nodes' spread fell short
/// of σ_p, and the courtyard board seen 45° from its normal read 1.49 / 6.7 % at m = 0.05 (mean /
/// p99), 1.15 / 4.9 % at 1.4 (with exact lookups 1.12 / 4.9 and 0.87 / 2.8 %). At 1.4 they lie at
/// 2.8σ_p; from 4/3 up to √3 the reach holds the same five nodes, so the step costs nothing.
pub const LATTICE_MAX_STEP: f64 = 1.4;
/// The share of the lobe's across-the-plane spread whose mean reflection each lattice node reads
/// ([`across_mean`], [`lattice_across_variance`]). A node's lookup is isotropic about its mirror
/// direction s, as if tilting h across the plane swung s along a great circle; it swings s along
/// a small circle, towards the horizon by 2(V·H)·q² for a tilt q, so the lobe's mass across the
/// plane lies below s. At a share of 1 (its mean, to second order) the lattice with exact lookups
/// read the courtyard board seen 45° from its normal at m = 0.05 (dark roofs under a bright sky,
/// all of it the residual's) at 0.23 / 1.8 % (mean / p99) instead of 0.87 / 2.8 %. But at 1 two
/// dark points of the 112 whose light is 4–6σ out in the lobe's tails at 1,000:1 read +5.1 and
/// +5.2 % (+3.3, +2.6 % without): the lookups at the nodes towards the horizon are as wide across
/// as the lobe at its centre, wider than it is there (the across Jacobian 2(V·H)(N·H) shrinks),
/// and moving them down moves those tails nearer the light. 0.7 keeps both under 5 % and most of
/// the gain (BENCHMARKS.md, "The lobe across the plane is curved").
pub const LATTICE_ACROSS_MEAN: f64 = 0.7;
/// The specular part of the `brdf` model for a narrow lobe, by a lattice along the plane of
/// incidence. The Beckmann slopes are Gaussian, σ = m/√2 per axis; mapped to reflected
/// directions, the lobe is 2·nv·σ wide across the plane and 2·σ along it. Each node reads the
/// layers at β = t·2·nv·σ (t = `LATTICE_BLUR_SHARE`), which supplies the width across the plane
/// (t a little under 1 measured better on a sphere: the lookups are a little wider than their
/// nominal blur, the lobe's profile across the plane lighter-tailed than their Gaussian) and a
/// share of the width along it; the nodes lie on the plane of incidence at slopes p spaced
/// `LATTICE_SPACING`·β/2 apart (at most `LATTICE_MAX_STEP`·σ_p), weighted by the Gaussian of the
/// rest of the in-plane variance,
/// σ_p² = σ² − (β/2)²,
/// times F·G·(V·H)/(nv·nh) (`lattice_taper` at the reach). Each node reads about the mean of
/// its reflections across the plane, not its mirror direction ([`across_mean`],
/// [`LATTICE_ACROSS_MEAN`]). At normal incidence that is one lookup; towards grazing, more (at
/// most 2·`LATTICE_MAX_HALF` + 1, the spacing and blur growing past that). Towards grazing
/// ([`lattice_own_widths`]) each node reads the lobe's width across the plane at its own half
/// vector ([`lattice_node_blur`]) and weighs the in-plane spread its own lookup leaves
/// ([`lattice_node_density`]), those weights tilted back to mean slope 0. Below layer 1's β the
/// nodes read the residual's own pixels instead ([`sharp_radiance`], where `sharp` has them), as
/// far as the lattice's node count allows ([`sharp_share`]). Normalised by A(nv) like
/// [`specular_quadrature`](super::brdf_quadrature::specular_quadrature).
pub fn specular_lattice(
    (env, sharp): (&PrefilteredEnvironment, Option<&SharpSource>),
    (brdf, fresnel, albedo): (&BrdfParams, &FresnelTable, &[[f32; 4]]),
    n: DVec3,
    v: DVec3,
) -> [f64; 3] {
    let Some(Incidence { nv, tangent, .. }) = incidence(n, v) else {
        return [0.0; 3];
    };
    let sigma = brdf.beckmann_m / std::f64::consts::SQRT_2;
    let beta0 = 2.0 * nv * sigma * LATTICE_BLUR_SHARE;
    // σ² − (β0/2)² = σ²·(1 − t² + t²·|N × V|²): 0 at normal incidence in f32 as in f64, where
    // 1 − nv² would leave the shader nodes a rounding apart, astride a cube edge under N.
    let t2 = LATTICE_BLUR_SHARE * LATTICE_BLUR_SHARE;
    let sigma_p = sigma
        * (1.0 - t2 + t2 * n.cross(v).length_squared())
            .max(0.0)
            .sqrt();
    let reach = LATTICE_REACH * sigma_p;
    let step = (LATTICE_SPACING * 0.5 * beta0)
        .min(LATTICE_MAX_STEP * sigma_p)
        .max(reach / f64::from(LATTICE_MAX_HALF));
    let beta = beta0.max(2.0 * step / LATTICE_SPACING);
    // At normal incidence σ_p, the reach and the step are 0: the mirror direction alone. Only
    // the nodes inside the reach: one at or beyond it has weight 0 (`lattice_taper`).
    let half = match step > 0.0 {
        true => ((reach / step).ceil() - 1.0).clamp(0.0, f64::from(LATTICE_MAX_HALF)) as i32,
        false => 0,
    };
    // Towards grazing each node reads its own width and weight ([`lattice_own_widths`]).
    let kappa = lattice_own_widths(nv);
    let beta1 = env.betas.get(1).copied().unwrap_or(0.0);
    let narrowest = beta * (1.0 - kappa * (1.0 - LATTICE_NODE_BLUR_FLOOR));
    let sharp = sharp.filter(|_| narrowest < beta1);
    let sharp_share = match (sharp, step > 0.0) {
        (Some(_), true) => sharp_share(reach / step),
        (Some(_), false) => 1.0,
        (None, _) => 0.0,
    };
    let read = |s: DVec3, blur: f64| {
        let layers = || layered_radiance(env, s, blur);
        match sharp.filter(|_| sharp_share > 0.0 && blur < beta1) {
            None => layers(),
            Some(source) => {
                let sharp = sharp_radiance(env, source, s, blur);
                match sharp_share < 1.0 {
                    true => {
                        let layers = layers();
                        std::array::from_fn(|c| layers[c] + (sharp[c] - layers[c]) * sharp_share)
                    }
                    false => sharp,
                }
            }
        }
    };
    // The own densities lean towards the nodes whose lookups are narrower: each weight g is
    // tilted by (1 − λ·p), λ = Σg·p / Σg·p², back to mean slope 0. The sums are linear in λ, so
    // one pass keeps the plain and the slope-weighted sums and λ's two moments.
    let (mut sums, mut moments) = (LookupSums::default(), LookupSums::default());
    let (mut first, mut second) = (0.0, 0.0);
    for i in -half..=half {
        let slope = f64::from(i) * step;
        let h = (tangent * slope + n).normalize();
        let (nh, vh) = (n.dot(h), v.dot(h));
        let own = lattice_node_blur(beta, sigma, nh, vh);
        let blur = beta + kappa * (own - beta);
        let gauss = match sigma_p > 0.0 {
            true => {
                let shared = (-0.5 * (slope / sigma_p).powi(2)).exp();
                let own = lattice_node_density((sigma, sigma_p, beta), slope, (n, v, h));
                (shared + kappa * (own - shared)) * lattice_taper(slope.abs() / reach)
            }
            false => 1.0,
        };
        first += gauss * slope;
        second += gauss * slope * slope;
        let across = lattice_across_variance(sigma, nh);
        let read = |s, vh| read(across_mean(s, h, vh, across), blur);
        if let Some((weight, radiance)) = lookup(fresnel, (n, v, nv), h, gauss, read) {
            sums.push(weight, radiance, 1.0);
            moments.push(weight, radiance, slope);
        }
    }
    let tilt = match kappa > 0.0 && second > 0.0 {
        true => first / second,
        false => 0.0,
    };
    sums.tilted(&moments, tilt).normalized(albedo, nv)
}

/// The share of each lattice node's own blur and density against the lattice's one, at nv
/// ([`LATTICE_OWN_WIDTHS`]): 1 up to its first nv, 0 from its second, a smoothstep between
/// (twin of brdf_environment.glsl's `lattice_own_widths`).
pub fn lattice_own_widths(nv: f64) -> f64 {
    let (full, none) = LATTICE_OWN_WIDTHS;
    1.0 - smoothstep01(((nv - full) / (none - full)).clamp(0.0, 1.0))
}

/// Where the lattice's nodes read their own widths ([`lattice_own_widths`]): fully up to nv =
/// 0.15, not from 0.35. Across the plane the lobe is (V·H)(N·H)/nv as wide at a node as at its
/// centre; towards grazing (at 80° from the normal, nv 0.17) about half at the nodes towards the
/// horizon and twice at the far ones, where one blur for all nodes read the studio board seen 80°
/// from its normal 2.02 / 11.8 % off at m = 0.05 (mean / p99), each node's own 0.98 / 5.7 %.
/// Nearer face-on the own widths gained little and lost some (the courtyard board at 45° 0.62 /
/// 3.3 → 0.69 / 3.8 %), and above the band the nodes share one layer pair, which is what keeps
/// the draw's cost: 0.35–0.65 read 0.96 / 5.5 % there and 0.54 / 3.6 % on the courtyard's 112
/// points (now 0.62 / 4.2 %), for a `brdf` draw 3 % dearer, over the bound of 1.5× `paper`
/// (BENCHMARKS.md, "Each lattice node at its own width" and "The own widths' band narrowed").
pub const LATTICE_OWN_WIDTHS: (f64, f64) = (0.15, 0.35);

/// The least share of the lattice's β a node's own blur takes ([`lattice_node_blur`]): towards
/// the horizon V·H falls to 0, and a node read sharper than its neighbours' spacing along the
/// plane would alias. Above 0.5 it bites at 80° from the normal (m = 0.05: 0.6 read 5.8 % p99,
/// 0.75 7.4 %, 1 18.5 %; BENCHMARKS.md, "Each lattice node at its own width").
pub const LATTICE_NODE_BLUR_FLOOR: f64 = 0.5;

/// A lattice node's own blur at half vector h (twin of brdf_environment.glsl's
/// `lattice_node_blur`): the lobe's width across the plane there times the blur share,
/// 2(V·H)(N·H)·σ·t (the across Jacobian is 2(V·H)(N·H), 2·nv at the mirror direction), but at
/// least [`LATTICE_NODE_BLUR_FLOOR`] of the lattice's β.
pub fn lattice_node_blur(beta: f64, sigma: f64, nh: f64, vh: f64) -> f64 {
    (2.0 * vh * nh * sigma * LATTICE_BLUR_SHARE).max(LATTICE_NODE_BLUR_FLOOR * beta)
}

/// A lattice node's own density along the plane at Beckmann slope `slope` (twin of
/// brdf_environment.glsl's `lattice_node_density`), relative to the shared Gaussian's peak: the
/// Gaussian of the in-plane spread its lookup leaves, σ² less the square of its own blur's
/// ([`lattice_node_blur`]) share along the plane, blur/(2(N·H)²) in slope (the reflection's
/// Jacobian along the plane is 2(N·H)²), normalised by its deviation and scaled by σ_p, so
/// that it is 1 at the mirror direction when the blur is the lattice's: the nodes whose lookups
/// are narrower spread wider. For the lobe's own share, 2(V·H)(N·H)·σ·t (where V·H > 0), the
/// variance is σ²·(1 − t²(V·H)²/(N·H)²), written without cancellation as (N·H)² − t²(V·H)² =
/// (1 − t²)(N·H)² + t²((N − V)·H)((N + V)·H); for the floor's, σ²·(1 − (fβ/(2(N·H)²σ))²); the
/// less of the two. 0 where the lookup alone is as wide along the plane as the lobe.
pub fn lattice_node_density(
    (sigma, sigma_p, beta): (f64, f64, f64),
    slope: f64,
    (n, v, h): (DVec3, DVec3, DVec3),
) -> f64 {
    let t2 = LATTICE_BLUR_SHARE * LATTICE_BLUR_SHARE;
    let nh = n.dot(h);
    // Beyond V·H = 0 the lobe's share is negative and the floor is the blur.
    let own = match v.dot(h) > 0.0 {
        true => ((1.0 - t2) * nh * nh + t2 * (n - v).dot(h) * (n + v).dot(h)) / (nh * nh),
        false => 1.0,
    };
    let floor = 1.0 - (LATTICE_NODE_BLUR_FLOOR * beta / (2.0 * nh * nh * sigma)).powi(2);
    let variance = sigma * sigma * own.min(floor);
    match variance > 0.0 {
        true => (-0.5 * slope * slope / variance).exp() * sigma_p / variance.sqrt(),
        false => 0.0,
    }
}

/// The across-the-plane slope variance whose mean reflection a lattice node at half vector h
/// reads ([`across_mean`]): [`LATTICE_ACROSS_MEAN`]·σ²·(N·H)². The Beckmann slopes are taken
/// from N: n + t·p + b·q_N is h·√(1 + p²) + b·q_N, so about the unit h the tilt is q = q_N·(N·H),
/// of variance σ²·(N·H)².
pub fn lattice_across_variance(sigma: f64, nh: f64) -> f64 {
    LATTICE_ACROSS_MEAN * sigma * sigma * nh * nh
}

/// The mean direction of the reflections s of V about the half vectors h + b·q, b across the
/// plane of incidence and q of variance `variance` (twin of brdf_environment.glsl's
/// `across_mean`). Tilting h across the plane swings s along a small circle about the plane's
/// tangent, not a great circle: s = (2(V·H)(h + b·q) − (1 + q²)V)/(1 + q²), so their mean is
/// s − 2(V·H)·E[q²]·h to second order, normalised. An isotropic lookup about s itself is that
/// far off the lobe's centre of mass.
pub fn across_mean(s: DVec3, h: DVec3, vh: f64, variance: f64) -> DVec3 {
    (s - 2.0 * vh * variance * h).normalize()
}

/// The lattice's share of sharp reads for its node count `reach/step` ([`SHARP_NODES`]): 1 up
/// to the first, 0 from the second, linear between.
pub fn sharp_share(nodes: f64) -> f64 {
    let (all, none) = SHARP_NODES;
    ((none - nodes) / (none - all)).clamp(0.0, 1.0)
}

/// A lookup at β below layer 1's β_1 from the map's own pixels ([`SharpSource`]): their Gaussian
/// at β, or where β is wider than a read there may be ([`SharpSource::widest_beta`]), the widest
/// read blended with layer 1 in variance as [`layered_radiance`] blends two layers.
pub fn sharp_radiance(
    env: &PrefilteredEnvironment,
    source: &SharpSource,
    d: DVec3,
    beta: f64,
) -> [f64; 3] {
    let beta1 = env.betas[1];
    let widest = source.widest_beta(d);
    let b = beta.min(widest);
    if b.is_nan() || b <= 0.0 {
        // At a pole's very point the map has no columns to read.
        return layered_radiance(env, d, beta);
    }
    let sharp = source.radiance(d, b);
    if beta <= b {
        return sharp;
    }
    let t = (beta * beta - b * b) / (beta1 * beta1 - b * b);
    let layer1 = cube_bilinear(&env.layers[1], d);
    std::array::from_fn(|c| sharp[c] + (layer1[c] - sharp[c]) * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lattice_node_reads_the_mean_of_its_reflections_across_the_plane() {
        // Brute force: the Beckmann slopes across the plane, q_N ~ N(0, σ²) from N, at a node of
        // slope p along it; the mean of the reflections of V about n + t·p + b·q_N, by a midpoint
        // sum over ±8σ. `across_mean` at the full variance agrees to O(σ⁴) (σ⁴ = 1.6e-6 here;
        // 2.6e-6 rad at worst); the mirror direction itself is O(σ²) away (7e-4 rad at θ_V = 0.3,
        // so a factor or a sign off in the mean would be 3e-4 and more).
        let sigma = 0.05 / std::f64::consts::SQRT_2;
        let n = DVec3::Z;
        for (theta_v, p) in [(0.3_f64, 0.0), (0.8, 0.04), (1.2, -0.06), (1.45, 0.02)] {
            let v = DVec3::new(theta_v.sin(), 0.0, theta_v.cos());
            let (t, b) = (DVec3::X, DVec3::Y);
            let reflect = |h: DVec3| {
                let h = h.normalize();
                2.0 * v.dot(h) * h - v
            };
            let steps = 4000;
            let mut mean = DVec3::ZERO;
            for i in 0..steps {
                let q = sigma * 16.0 * ((f64::from(i) + 0.5) / f64::from(steps) - 0.5);
                mean += (-0.5 * (q / sigma).powi(2)).exp() * reflect(n + t * p + b * q);
            }
            let want = mean.normalize();
            let h = (n + t * p).normalize();
            let (vh, s) = (v.dot(h), reflect(h));
            let variance = lattice_across_variance(sigma, n.dot(h)) / LATTICE_ACROSS_MEAN;
            let got = across_mean(s, h, vh, variance);
            let angle = |a: DVec3, b: DVec3| a.cross(b).length().atan2(a.dot(b));
            assert!(
                angle(got, want) < 1e-5,
                "θ_V {theta_v}: {}",
                angle(got, want)
            );
            assert!(angle(s, want) > 2e-4, "θ_V {theta_v}: {}", angle(s, want));
        }
    }

    #[test]
    fn a_lattice_nodes_density_is_its_spread_less_its_own_blur() {
        // Against the definition written directly: σ² less the square of the node's own blur's
        // share along the plane, blur/(2(N·H)²), the Gaussian at that variance over its
        // deviation, times σ_p. The cancellation-free form agrees to rounding (1e-12 relative);
        // a sign or a factor wrong in it moves the variance by t²(V·H)² or more, 10⁻¹ here.
        let sigma = 0.05 / std::f64::consts::SQRT_2;
        let n = DVec3::Z;
        for theta_v in [0.3_f64, 0.9, 1.3, 1.5] {
            let v = DVec3::new(theta_v.sin(), 0.0, theta_v.cos());
            let nv = v.z;
            let t = LATTICE_BLUR_SHARE;
            let beta = 2.0 * nv * sigma * t;
            let sigma_p = sigma * (1.0 - (t * nv).powi(2)).sqrt();
            for slope in [-0.12, -0.05, 0.0, 0.03, 0.1] {
                let h = DVec3::new(slope, 0.0, 1.0).normalize();
                let (nh, vh) = (n.dot(h), v.dot(h));
                let blur = lattice_node_blur(beta, sigma, nh, vh);
                let variance = sigma * sigma - (blur / (2.0 * nh * nh)).powi(2);
                let want = match variance > 0.0 {
                    true => (-0.5 * slope * slope / variance).exp() * sigma_p / variance.sqrt(),
                    false => 0.0,
                };
                let got = lattice_node_density((sigma, sigma_p, beta), slope, (n, v, h));
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1e-300),
                    "θ_V {theta_v}, slope {slope}: {got} {want}"
                );
            }
        }
    }
}
