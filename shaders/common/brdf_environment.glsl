// SPEC §4's `brdf` environment model, specular half: ∫ f_spec(N, V, s)·L(s)·(N·s) dω_s by a fixed
// quadrature. The CPU twin is src/environment/brdf_quadrature.rs (the lattice's part in
// brdf_lattice.rs): change both together, formula by formula.
//
// Three quadratures of the lookups, picked (or two blended) by the material's m: for a narrow
// lobe (m ≤ 0.06) a lattice of nodes on the plane of incidence, each read at the blur that gives
// the lobe's width across the plane (`specular_lattice`: three lookups near normal incidence, up
// to 49 at grazing); for a middling one (0.07 ≤ m ≤ 0.22, the rough preset) a grid of slopes
// from the lobe's Gaussian less the lookups' blur (`specular_grid`, 377 lookups face-on, 2,205 at grazing); for a wide one
// (m ≥ 0.3) `samples` half vectors from a Fibonacci lattice in the Beckmann
// lobe, in a frame whose first axis lies in the plane of incidence; each reflected direction s
// weighs F(acos V·H)·G·(V·H)/(nv·nh) and reads the layers at the β whose lobe covers its share
// 1/(samples·pdf(s)) of the sphere (filtered importance sampling, `specular_fis`). The
// lookups are bilinear by hand from the layers' texels
// (`env_layer_texels`), with one seam rule, the twin's: a tap beyond its face reads the texel
// holding the tap's direction on the face that direction selects. Each face is stored with a
// one-texel apron that holds those texels (layer_apron.comp), so a lookup reads four texels
// without a branch, stored two to a texel (layer_pair.glsl): two reads. The sampler's own cube
// filtering leaves the edges and corners to the implementation.
//
// The layers it reads are the residual of the map's bright split (environment/bright.rs); the
// bright parts come back as the frame's `env_light_*` lights, each through the lobe widened by its
// spread (`bright_specular`). Where the camera looks, the grid and filtered importance sampling
// read the rough split instead (`split_bright_rough`: every bright block a light, so no light box
// is left in the layers for a lobe's tails to meet), and so does the lattice from
// `frame.env_lattice_share.y` up: its residual's texels from `frame.env_rough.x`, its lights
// `env_rough_light_*`, which a narrow lobe visits through their direction bins
// (`binned_rough_bright_specular`).
//
// The includer includes frame.glsl and lacquer_brdf.glsl first and binds ENV_LAYER_TEXELS_BINDING.

#ifndef BRDF_ENVIRONMENT_GLSL
#define BRDF_ENVIRONMENT_GLSL

#include "cubemap.glsl"
#include "texel_buffer.glsl"
#include "layer_pair.glsl"
#include "visible_normals.glsl"
// Two texels of a layer's face rows in each (layer_pair.glsl).
layout(set = 0, binding = ENV_LAYER_TEXELS_BINDING) uniform utextureBuffer env_layer_texels;

// Lobe samples of filtered importance sampling where the camera looks and at the paths' hits
// (brdf_quadrature.rs `BRDF_SAMPLES`, `BRDF_HIT_SAMPLES`).
layout(constant_id = ENV_SAMPLES_ID) const int ENV_SAMPLES = 1024;
layout(constant_id = ENV_HIT_SAMPLES_ID) const int ENV_HIT_SAMPLES = 32;

// A lookup's two layers as `layer_pair_of_run` found them for its β, with where each one's
// texels are: its face size and its first texel (from `base`: 0 for the residual's layers,
// `frame.env_rough.x` for the rough split's, laid out the same after them). Read from the frame
// once per β: a per-lane index into the frame is a gather lane by lane on llvmpipe, and a lattice
// reads its one pair at every node.
struct LayerPair {
    int size0;
    int first0;
    int size1;
    int first1;
    float t;
};

LayerPair layer_pair_texels(float beta, int base) {
    int k0;
    float t;
    layer_pair_of_run(beta, k0, t);
    int k1 = min(k0 + 1, ENV_LAYER_COUNT - 1);
    return LayerPair(frame.layer_face_size[k0 / 4][k0 % 4],
        base + frame.layer_first_texel[k0 / 4][k0 % 4], frame.layer_face_size[k1 / 4][k1 % 4],
        base + frame.layer_first_texel[k1 / 4][k1 % 4], t);
}

// That layer at the direction that select_face put at (face, st), bilinear over the four texel
// centres around it. Each face is stored with a one-texel apron (layer_apron.comp): a tap beyond
// the face reads the apron texel, which holds the texel of the tap's direction on the face that
// direction selects, so every lookup reads four texels of one face's rows, without a branch: two
// pairs (layer_pair.glsl), (x0, x0 + 1) of rows y0 and y0 + 1.
vec3 layer_bilinear(int isize, int first, int face, vec2 st) {
    float size = float(isize);
    vec2 xy = (st + 1.0) * 0.5 * size - 0.5;
    vec2 xy0 = floor(xy);
    vec2 f = xy - xy0;
    // Taps x0 and x0 + 1 in [−1, M]: apron columns and rows 0 and M + 1.
    ivec2 ij = whole_to_int(xy0 + 1.0);
    int stride = isize + 2;
    int row = first + (face * stride + ij.y) * stride + ij.x;
    uvec4 upper = texelFetch(env_layer_texels, row);
    uvec4 lower = texelFetch(env_layer_texels, row + stride);
    vec3 a = layer_first(upper);
    vec3 b = layer_second(upper);
    vec3 c = layer_first(lower);
    vec3 e = layer_second(lower);
    vec3 top = a + (b - a) * f.x;
    vec3 bottom = c + (e - c) * f.x;
    return top + (bottom - top) * f.y;
}

// Lpre(d, β) from the layers of `pair` (`layer_pair_texels` for β): the same layers and blend as
// `prefiltered_radiance`, read by hand (a quadrature whose lookups share one β finds them once).
vec3 layered_radiance_pair(vec3 d, LayerPair pair) {
    // Both layers see d on the same face at the same (s, t).
    int face;
    vec2 st;
    select_face(d, face, st);
    vec3 lo = layer_bilinear(pair.size0, pair.first0, face, st);
    if (pair.t == 0.0) {
        return lo;
    }
    vec3 hi = layer_bilinear(pair.size1, pair.first1, face, st);
    return lo + (hi - lo) * pair.t;
}

// A(nv) from the object's ALBEDO_KNOTS knots (nv, A_r, A_g, A_b) at nv = (k/(ALBEDO_KNOTS − 1))²
// among the Fresnel knots, linear in √nv between knots (twin of brdf_quadrature.rs `albedo_at`).
vec3 albedo_at(int first, float nv) {
    int last = ALBEDO_KNOTS - 1;
    float x = sqrt(clamp(nv, 0.0, 1.0)) * float(last);
    int k = min(whole_to_int(floor(x)), last - 1);
    float t = x - float(k);
    vec3 a = texelFetch(fresnel_knots, first + k).yzw;
    vec3 b = texelFetch(fresnel_knots, first + k + 1).yzw;
    return a + (b - a) * t;
}

// D convolved with a light's spread σ² (twin: brdf_quadrature.rs `spread_beckmann_d`, whose
// doc derives it): in slope space, m_x² = m² + σ²/2 along the plane of V and l, m_y² = m² +
// σ²/(2·(V·H)²) across it; c = N × H. Written over b = m_y²·(V·H)² so that it divides twice.
float spread_beckmann_d(float m, float spread, vec3 n, vec3 v, vec3 l, float nh, float vh, vec3 c) {
    float nh2 = nh * nh;
    vec3 across = cross(v, l);
    float ne = dot(n, across);
    float ne2 = ne * ne;
    // tan²θ_H and its part across the plane, y² = (N·e)²/(1 − (N·e)²), e = across/|across|,
    // over the common denominator nh²·(|across|² − (N·e)²·|across|²).
    // V ∥ l (no plane; H = V): all of tan²θ_H along, over nh² alone.
    float rest = dot(across, across) - ne2;
    bool plane = rest > 0.0;
    float den = plane ? nh2 * rest : nh2;
    float tan2_den = plane ? dot(c, c) * rest : dot(c, c);
    float y2_den = plane ? min(ne2 * nh2, tan2_den) : 0.0;
    float x2_den = tan2_den - y2_den;
    float m2 = m * m;
    float mx2 = m2 + 0.5 * spread;
    float vh2 = vh * vh;
    float b = m2 * vh2 + 0.5 * spread;
    float q = mx2 * b;
    return vh * exp(-(x2_den * b + y2_den * mx2 * vh2) / (den * q)) / (PI * sqrt(q) * nh2 * nh2);
}

// cos 2θ_max for a light of spread σ²: tan²θ_max = BRIGHT_LOBE_CULL·(m² + σ²/2), the slopes where
// the widened D is above e^-9 of its peak, without trigonometry (twin: brdf_quadrature.rs
// `light_cull_cos`, and light_bins.rs relies on it).
float light_cull_cos(LacquerParams p, float spread) {
    float t2 = float(BRIGHT_LOBE_CULL) * (p.beckmann_m * p.beckmann_m + 0.5 * spread);
    return (1.0 - t2) / (1.0 + t2);
}

// One of the map's bright parts, taken out of the layers as a directional light (environment/
// bright.rs; xyz towards it and w its spread σ²), per unit of its irradiance E: f_spec·E·(N·l) =
// F·D'·G·E/(4·nv) with D' the lobe widened by the spread, less the E; 0 for a light beyond
// `light_cull_cos` of the mirror direction r (twin: brdf_quadrature.rs `bright_light`). The
// caller multiplies by E, and reads it only where this is not 0.
vec3 bright_light_weight(LacquerParams p, vec3 n, vec3 v, float nv, vec3 r, vec4 light) {
    vec3 l = light.xyz;
    if (dot(r, l) < light_cull_cos(p, light.w)) {
        return vec3(0.0);
    }
    float nl = dot(n, l);
    vec3 half_sum = v + l;
    float half_len = length(half_sum);
    if (nl <= 0.0 || half_len <= 0.0) {
        return vec3(0.0);
    }
    vec3 h = half_sum / half_len;
    float nh = dot(n, h);
    float vh = dot(v, h);
    if (nh <= 0.0 || vh <= 0.0) {
        return vec3(0.0);
    }
    float d = spread_beckmann_d(p.beckmann_m, light.w, n, v, l, nh, vh, cross(n, h));
    float g = cook_torrance_g(nh, nv, nl, vh);
    vec3 f = lacquer_fresnel(p, angle_deg_of_cos(min(vh, 1.0)));
    return f * (d * g / (4.0 * nv));
}

// The bright split's lights (`env_light_*`; twin: `bright_specular`).
vec3 bright_specular(LacquerParams p, vec3 n, vec3 v, float nv) {
    vec3 r = 2.0 * nv * n - v;
    vec3 sum = vec3(0.0);
    for (int i = 0; i < frame.environment.z; ++i) {
        sum += bright_light_weight(p, n, v, nv, r, frame.env_light_direction[i])
            * frame.env_light_irradiance[i].rgb;
    }
    return sum;
}

// The rough split's lights (`env_rough_light_*`; twin: `bright_specular` of them).
vec3 rough_bright_specular(LacquerParams p, vec3 n, vec3 v, float nv) {
    vec3 r = 2.0 * nv * n - v;
    vec3 sum = vec3(0.0);
    for (int i = 0; i < frame.env_rough.y; ++i) {
        sum += bright_light_weight(p, n, v, nv, r, frame.env_rough_light_direction[i])
            * frame.env_rough_light_irradiance[i].rgb;
    }
    return sum;
}

// The cell of the rough lights' direction bins holding d (twin: light_bins.rs `light_bin`).
int light_bin(vec3 d) {
    int face;
    vec2 st;
    select_face(d, face, st);
    ivec2 cell = min(whole_to_int(floor((st + 1.0) * (0.5 * float(ENV_LIGHT_BIN_CELLS)))),
        ivec2(ENV_LIGHT_BIN_CELLS - 1));
    return (face * ENV_LIGHT_BIN_CELLS + cell.y) * ENV_LIGHT_BIN_CELLS + cell.x;
}

// `rough_bright_specular` for m up to frame.env_lattice_share.z, visiting only the lights listed
// in the direction bin of the mirror direction (environment/light_bins.rs, which holds each
// listed light's direction and irradiance): the others would add an exact 0, and the listed ones
// are added in the same order, so the sum is the same number. A light's irradiance is read only
// where its weight is not 0: the read is a gather, and llvmpipe skips it wherever the whole block
// of pixels culls the light (measured in BENCHMARKS.md, "Two layer texels in one").
vec3 binned_rough_bright_specular(LacquerParams p, vec3 n, vec3 v, float nv) {
    vec3 r = 2.0 * nv * n - v;
    int headers = frame.env_rough.z;
    int list = headers + 6 * ENV_LIGHT_BIN_CELLS * ENV_LIGHT_BIN_CELLS;
    vec2 bin = texelFetch(fresnel_knots, headers + light_bin(r)).xy;
    int first = whole_to_int(bin.x);
    int count = whole_to_int(bin.y);
    vec3 sum = vec3(0.0);
    for (int k = first; k < first + count; ++k) {
        vec3 weight = bright_light_weight(p, n, v, nv, r, texelFetch(fresnel_knots, list + 2 * k));
        if (any(notEqual(weight, vec3(0.0)))) {
            sum += weight * texelFetch(fresnel_knots, list + 2 * k + 1).rgb;
        }
    }
    return sum;
}

// One lookup of either quadrature: the reflection s of v about the half vector h (vh = V·H > 0),
// weighted by scale·F(acos V·H)·G·(V·H)/(nv·nh); false where s is below the surface (twin:
// `LookupSums::add_read`).
bool lookup_weight(LacquerParams p, vec3 n, vec3 v, float nv, vec3 h, float vh, float scale,
    out vec3 s, out vec3 weight) {
    s = 2.0 * vh * h - v;
    weight = vec3(0.0);
    float nl = dot(n, s);
    if (nl <= 0.0) {
        return false;
    }
    float cos_h = dot(n, h);
    float g = cook_torrance_g(cos_h, nv, nl, vh);
    vec3 f = lacquer_fresnel(p, angle_deg_of_cos(min(vh, 1.0)));
    weight = f * (scale * g * vh / (nv * cos_h));
    return true;
}

// `lookup_weight`'s lookup read at β from the layers of `pair` (twin: `LookupSums::add`).
void add_lookup_pair(LacquerParams p, vec3 n, vec3 v, float nv, vec3 h, float vh, float scale,
    LayerPair pair, inout vec3 sum, inout vec3 weights) {
    vec3 s;
    vec3 weight;
    if (lookup_weight(p, n, v, nv, h, vh, scale, s, weight)) {
        sum += weight * layered_radiance_pair(s, pair);
        weights += weight;
    }
}

void add_lookup(LacquerParams p, vec3 n, vec3 v, float nv, vec3 h, float vh, float scale,
    float beta, int base, inout vec3 sum, inout vec3 weights) {
    add_lookup_pair(p, n, v, nv, h, vh, scale, layer_pair_texels(beta, base), sum, weights);
}

// Σ w·L / Σ w · A(nv) per channel: exact in a white furnace (twin: `LookupSums::normalized`).
vec3 normalized_lookups(LacquerParams p, float nv, vec3 sum, vec3 weights) {
    vec3 a = albedo_at(p.albedo_first, nv);
    return vec3(weights.r > 0.0 ? sum.r / weights.r * a.r : 0.0,
                weights.g > 0.0 ? sum.g / weights.g * a.g : 0.0,
                weights.b > 0.0 ? sum.b / weights.b * a.b : 0.0);
}

// The frame of the plane of incidence: the tangent towards V's projection (any axis at normal
// incidence, where the pattern's orientation does not matter), and N × tangent.
void incidence_frame(vec3 n, vec3 v, float nv, out vec3 tangent, out vec3 bitangent) {
    vec3 along = v - nv * n;
    float along2 = dot(along, along);
    vec3 other = abs(n.x) < 0.5 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    tangent = along2 > 1e-12 ? along * inversesqrt(along2) : normalize(cross(n, other));
    bitangent = cross(n, tangent);
}

// Each quadrature's share of the lookups for roughness m: (lattice, grid, filtered importance
// sampling); at a path's hit (camera false) filtered importance sampling takes the grid's share
// (twin: `quadrature_shares`).
vec3 quadrature_shares(float m, bool camera) {
    vec4 band = frame.env_lattice_band;
    float lattice = clamp((band.y - m) / (band.y - band.x), 0.0, 1.0);
    float fis = clamp((m - band.z) / (band.w - band.z), 0.0, 1.0);
    return camera ? vec3(lattice, 1.0 - lattice - fis, fis) : vec3(lattice, 0.0, 1.0 - lattice);
}

// 3t² − 2t³ on [0, 1], written out as its twin `smoothstep01` has it.
float smoothstep01(float t) {
    return t * t * (3.0 - 2.0 * t);
}

// 1 inside the reach, a smoothstep to 0 over its last `taper` share (twin: `lattice_taper`).
float lattice_taper(float x) {
    return smoothstep01(clamp((1.0 - x) / frame.env_lattice.z, 0.0, 1.0));
}

// Φ(x), the standard normal distribution (twin: sharp_source.rs `normal_cdf`).
float normal_cdf(float x) {
    float tail = 0.5 * erfc_positive(abs(x) * 0.70710678);
    return x >= 0.0 ? 1.0 - tail : tail;
}

// The widest β a sharp read at e (the environment's frame) takes: frame.env_sharp_read.x
// (`SHARP_SIGMA`) of a row's height or a column's width there (twin: `SharpSource::widest_beta`).
float sharp_widest_beta(vec3 e) {
    float row = PI / float(frame.env_sharp.w);
    float column = 2.0 * PI / float(frame.env_sharp.z) * length(e.xz);
    return frame.env_sharp_read.x * min(row, column);
}

// The most rows a sharp read covers: 2·SHARP_REACH·SHARP_SIGMA + 1 = 7, and one for rounding.
const int SHARP_MAX_ROWS = 8;

// A residual's own pixels from texel `first` at e (the environment's frame) through a Gaussian of
// width β ≤ `sharp_widest_beta` (twin: `SharpSource::radiance`, whose module doc derives it):
// each pixel weighs the normal distribution's share of its column times its row's, out to
// frame.env_sharp_read.y σ, whole texels (pixel pairs) at a time.
vec3 sharp_pixels(int first, vec3 e, float beta) {
    vec2 uv = direction_to_equirect(e);
    int width = frame.env_sharp.z;
    int height = frame.env_sharp.w;
    float x = uv.x * float(width);
    float y = uv.y * float(height);
    float sigma_y = beta * float(height) / PI;
    float sigma_x = beta * float(width) / (2.0 * PI * length(e.xz));
    float reach = frame.env_sharp_read.y;
    int top = signed_whole_to_int(floor(y - reach * sigma_y));
    int bottom = min(signed_whole_to_int(floor(y + reach * sigma_y)), top + SHARP_MAX_ROWS - 1);
    // Rows beyond the poles are no pixels: those inside are normalised.
    float row_weight[SHARP_MAX_ROWS];
    for (int j = top; j <= bottom; ++j) {
        row_weight[j - top] = (j >= 0 && j < height)
            ? normal_cdf((float(j) + 1.0 - y) / sigma_y) - normal_cdf((float(j) - y) / sigma_y)
            : 0.0;
    }
    int first_pair = signed_whole_to_int(floor(floor(x - reach * sigma_x) * 0.5));
    int last_pair = signed_whole_to_int(floor(floor(x + reach * sigma_x) * 0.5));
    int pairs = width / 2;
    vec3 sum = vec3(0.0);
    float total = 0.0;
    float left = normal_cdf((float(2 * first_pair) - x) / sigma_x);
    for (int pair = first_pair; pair <= last_pair; ++pair) {
        float middle = normal_cdf((float(2 * pair) + 1.0 - x) / sigma_x);
        float right = normal_cdf((float(2 * pair) + 2.0 - x) / sigma_x);
        float w0 = middle - left;
        float w1 = right - middle;
        left = right;
        // Columns wrap: a pair is at most two beyond either end, so one add or subtract is the
        // remainder (integer % is not vectorised on lavapipe).
        int column = pair < 0 ? pair + pairs : (pair >= pairs ? pair - pairs : pair);
        for (int j = max(top, 0); j <= min(bottom, height - 1); ++j) {
            uvec4 texel = texelFetch(env_layer_texels, first + j * pairs + column);
            float wy = row_weight[j - top];
            sum += wy * (w0 * layer_first(texel) + w1 * layer_second(texel));
            total += wy * (w0 + w1);
        }
    }
    return total > 0.0 ? sum / total : vec3(0.0);
}

// A lattice lookup at β below layer 1's from a residual's own pixels (twin: `sharp_radiance`):
// their Gaussian at β, or where β is wider than a read there may be, the widest read blended with
// layer 1 (`layer1`, read alone) in variance; `layers` the layers' lookup at d for β, which is the
// answer at a pole's point.
vec3 sharp_radiance(int first, vec3 d, float beta, vec3 layers, LayerPair layer1) {
    vec3 e = world_to_environment(d, frame.env_sharp_rotation.x, frame.env_sharp_rotation.y);
    float b = min(beta, sharp_widest_beta(e));
    if (!(b > 0.0)) {
        return layers;
    }
    vec3 sharp = sharp_pixels(first, e, b);
    if (beta <= b) {
        return sharp;
    }
    float beta1 = layer_beta(1);
    float t = (beta * beta - b * b) / (beta1 * beta1 - b * b);
    vec3 layer = layered_radiance_pair(d, layer1);
    return sharp + (layer - sharp) * t;
}

// A lattice node's weight at Beckmann slope `slope`: the Gaussian of the in-plane spread σ_p,
// tapered at the reach; 1 at normal incidence, where σ_p is 0 (twin: `specular_lattice`).
float lattice_node_weight(float slope, float sigma_p, float reach) {
    return sigma_p > 0.0
        ? exp(-0.5 * (slope / sigma_p) * (slope / sigma_p)) * lattice_taper(abs(slope) / reach)
        : 1.0;
}

// The mean direction of the reflections of v about h tilted across the plane of incidence by
// slopes of variance `variance` (twin: `across_mean`, whose doc derives it), not normalised: the
// layers' face selection divides by the major axis (`select_face`), so only the sharp reads,
// which take angles, normalise it.
vec3 across_mean(vec3 s, vec3 h, float vh, float variance) {
    return s - 2.0 * vh * variance * h;
}

// The across-the-plane slope variance about a lattice node's h (twin: `lattice_across_variance`).
float lattice_across_variance(float sigma, float nh) {
    return frame.env_lattice_across.x * sigma * sigma * nh * nh;
}

// The share of each lattice node's own blur and density at nv: 1 up to
// frame.env_lattice_across.z, 0 from .w, a smoothstep between (twin: `lattice_own_widths`).
float lattice_own_widths(float nv) {
    vec2 band = frame.env_lattice_across.zw;
    return 1.0 - smoothstep01(clamp((nv - band.x) / (band.y - band.x), 0.0, 1.0));
}

// A lattice node's own blur: 2(V·H)(N·H)·σ·t, at least frame.env_lattice_across.y of the
// lattice's β (twin: `lattice_node_blur`).
float lattice_node_blur(float beta, float sigma, float nh, float vh) {
    return max(2.0 * vh * nh * sigma * frame.env_lattice_share.x,
        frame.env_lattice_across.y * beta);
}

// A lattice node's blur where `kappa` of its own width applies (twin: `specular_lattice`).
float lattice_blur_at(float beta, float kappa, float sigma, float nh, float vh) {
    return beta + kappa * (lattice_node_blur(beta, sigma, nh, vh) - beta);
}

// A lattice node's own density along the plane, relative to the shared Gaussian's peak (twin:
// `lattice_node_density`, whose doc derives it): `spread` σ, σ_p, β.
float lattice_node_density(vec3 spread, float slope, vec3 n, vec3 v, vec3 h) {
    float sigma = spread.x;
    float t2 = frame.env_lattice_share.x * frame.env_lattice_share.x;
    float nh = dot(n, h);
    // Beyond V·H = 0 the lobe's share is negative and the floor is the blur.
    float own = dot(v, h) > 0.0
        ? ((1.0 - t2) * nh * nh + t2 * dot(n - v, h) * dot(n + v, h)) / (nh * nh)
        : 1.0;
    float floor_share = frame.env_lattice_across.y * spread.z / (2.0 * nh * nh * sigma);
    float variance = sigma * sigma * min(own, 1.0 - floor_share * floor_share);
    return variance > 0.0 ? exp(-0.5 * slope * slope / variance) * spread.y / sqrt(variance)
        : 0.0;
}

// The four layers from the one `layer_pair_of_run` finds for β on: their read variances (layer
// 0's texels' own, β_k² from layer 1, LAYER_PAST past the last layer), face sizes and first
// texels (from `base`). Read once a pixel: the nodes of `lattice_by_node` that read their own
// widths pick their pair from it with selects (`pair_in_window`), where a per-node
// `layer_pair_texels` is a gather lane by lane on llvmpipe for each of its four numbers.
struct LayerWindow {
    vec4 variance;
    ivec4 size;
    ivec4 first;
    // The least variance the window holds a pair for: 0 from layer 0, its first layer's above.
    float lowest;
};

// Beyond every layer's β²: a finite number, as the blend divides by it (t is then ~0, and past
// the last layer both of a pair's layers are the last).
const float LAYER_PAST = 3.0e38;

LayerWindow layer_window(float beta, int base) {
    int k0;
    float t;
    layer_pair_of_run(beta, k0, t);
    LayerWindow w;
    int last = ENV_LAYER_COUNT - 1;
    for (int j = 0; j < 4; ++j) {
        int k = min(k0 + j, last);
        float b = layer_beta(k);
        w.variance[j] = k0 + j > last ? LAYER_PAST : (k == 0 ? frame.layer_variance.x : b * b);
        w.size[j] = frame.layer_face_size[k / 4][k % 4];
        w.first[j] = base + frame.layer_first_texel[k / 4][k % 4];
    }
    // Off the geometric run the blend is `layer_pair`'s, in log β: no window.
    w.lowest = frame.layer_run.z == 0.0 ? LAYER_PAST : (k0 == 0 ? 0.0 : w.variance.x);
    return w;
}

// The pair `layer_pair_texels` finds for `blur`, from the window: the blend in variance, t ≈ 0 on
// the last layer (the same layer twice); size0 = −1 where blur is outside the window.
LayerPair pair_in_window(LayerWindow w, float blur) {
    float x = blur * blur;
    int j = int(x >= w.variance.y) + int(x >= w.variance.z) + int(x >= w.variance.w);
    bool a = j == 0;
    bool b = j == 1;
    float lo = a ? w.variance.x : (b ? w.variance.y : w.variance.z);
    float hi = a ? w.variance.y : (b ? w.variance.z : w.variance.w);
    LayerPair pair = LayerPair(a ? w.size.x : (b ? w.size.y : w.size.z),
        a ? w.first.x : (b ? w.first.y : w.first.z), a ? w.size.y : (b ? w.size.z : w.size.w),
        a ? w.first.y : (b ? w.first.z : w.first.w), clamp((x - lo) / (hi - lo), 0.0, 1.0));
    pair.size0 = x >= w.lowest && j < 3 ? pair.size0 : -1;
    return pair;
}

// `specular_lattice`'s nodes where they read their own widths (`kappa` of them, towards
// grazing) or the residual's own pixels (below layer 1's β, by `shape.w`, the node count's share
// of them, the layers the rest): `along` its plane's tangent and step, `shape` its σ_p, reach,
// β; `pair` the layers for β (twin: `specular_lattice`).
vec3 lattice_by_node(LacquerParams p, vec3 n, vec3 v, float nv, vec4 along, vec4 shape,
    float kappa, int half_count, LayerPair pair, int base) {
    float sigma_p = shape.x;
    float reach = shape.y;
    float beta = shape.z;
    float sharp_share = shape.w;
    float sigma = p.beckmann_m * 0.70710678;
    float beta1 = layer_beta(1);
    int first = base == 0 ? frame.env_sharp.x : frame.env_sharp.y;
    // Layer 1 alone, for the widest read's blend with it.
    LayerPair layer1 = LayerPair(frame.layer_face_size[0][1], base + frame.layer_first_texel[0][1],
        frame.layer_face_size[0][1], base + frame.layer_first_texel[0][1], 0.0);
    // The plain and the slope-weighted sums, and the moments of the tilt λ (twin's comment).
    vec3 sum = vec3(0.0);
    vec3 weights = vec3(0.0);
    vec3 sum_p = vec3(0.0);
    vec3 weights_p = vec3(0.0);
    float first_moment = 0.0;
    float second_moment = 0.0;
    // A node's blur grows with its slope up to tan(θ_V/2) (its (V·H)(N·H) is (nv + slope·sin θ_V)
    // / (1 + slope²)), beyond the reach at every m the lattice serves: the first node's is the
    // least, and the window starts at its pair. A node beyond the window finds its own pair.
    vec3 h_first = normalize(along.xyz * (-float(half_count) * along.w) + n);
    LayerWindow window = layer_window(lattice_blur_at(beta, kappa, sigma, dot(n, h_first),
        dot(v, h_first)), base);
    for (int i = -half_count; i <= half_count; ++i) {
        float slope = float(i) * along.w;
        vec3 h = normalize(along.xyz * slope + n);
        float nh = dot(n, h);
        float vh = dot(v, h);
        float blur = lattice_blur_at(beta, kappa, sigma, nh, vh);
        float gauss = 1.0;
        if (sigma_p > 0.0) {
            float common_weight = exp(-0.5 * (slope / sigma_p) * (slope / sigma_p));
            float own = lattice_node_density(vec3(sigma, sigma_p, beta), slope, n, v, h);
            gauss = (common_weight + kappa * (own - common_weight))
                * lattice_taper(abs(slope) / reach);
        }
        first_moment += gauss * slope;
        second_moment += gauss * slope * slope;
        vec3 s;
        vec3 weight;
        if (gauss > 0.0 && vh > 0.0 && lookup_weight(p, n, v, nv, h, vh, gauss, s, weight)) {
            s = normalize(across_mean(s, h, vh, lattice_across_variance(sigma, nh)));
            LayerPair node_pair = kappa > 0.0 ? pair_in_window(window, blur) : pair;
            if (node_pair.size0 < 0) {
                node_pair = layer_pair_texels(blur, base);
            }
            // The layers' lookup first, on every node: the sharp read's branch, which most
            // nodes do not take, then holds the sharp read alone, not a second copy of the
            // layers' lookup that llvmpipe pays for under its lane mask (BENCHMARKS.md, "Where a
            // gather's cost goes").
            vec3 radiance = layered_radiance_pair(s, node_pair);
            if (sharp_share > 0.0 && blur < beta1) {
                vec3 sharp = sharp_radiance(first, s, blur, radiance, layer1);
                radiance = sharp_share < 1.0 ? radiance + (sharp - radiance) * sharp_share : sharp;
            }
            sum += weight * radiance;
            weights += weight;
            sum_p += slope * weight * radiance;
            weights_p += slope * weight;
        }
    }
    float tilt = kappa > 0.0 && second_moment > 0.0 ? first_moment / second_moment : 0.0;
    return normalized_lookups(p, nv, sum - tilt * sum_p, weights - tilt * weights_p);
}

// The narrow-lobe quadrature (twin: `specular_lattice`, whose doc derives it): nodes on the plane
// of incidence at Beckmann slopes i·step, each read at the blur β that supplies the lobe's width
// across the plane, about the mean of its reflections across the plane (`across_mean`), weighted
// by the Gaussian of the rest of the in-plane spread.
vec3 specular_lattice(LacquerParams p, vec3 n, vec3 v, float nv, int base) {
    vec3 tangent, bitangent;
    incidence_frame(n, v, nv, tangent, bitangent);
    float spacing = frame.env_lattice.x;
    float max_half = frame.env_lattice.w;
    float sigma = p.beckmann_m * 0.70710678;
    float share = frame.env_lattice_share.x;
    float beta0 = 2.0 * nv * sigma * share;
    // σ² − (β0/2)² without cancellation: 0 at normal incidence (twin's comment).
    vec3 nxv = cross(n, v);
    float sigma_p = sigma * sqrt(max(1.0 - share * share + share * share * dot(nxv, nxv), 0.0));
    float reach = frame.env_lattice.y * sigma_p;
    float step = max(min(spacing * 0.5 * beta0, frame.env_lattice_share.w * sigma_p),
        reach / max_half);
    float beta = max(beta0, 2.0 * step / spacing);
    // At normal incidence σ_p, the reach and the step are 0: the mirror direction alone. Only
    // the nodes inside the reach: one at or beyond it has weight 0.
    int half_count = step > 0.0
        ? whole_to_int(clamp(ceil(reach / step) - 1.0, 0.0, max_half))
        : 0;
    // Every node but those towards grazing reads the same blur: its layers, their texels and the
    // blend found once.
    LayerPair pair = layer_pair_texels(beta, base);
    // Towards grazing each node's own blur and density; below layer 1's β the residual's own
    // pixels, by the node count's share (twin: `sharp_share`). Both in a loop of their own: inline
    // in the shared pair's loop the sharp reads cost the default scene's `brdf` draw, which reads
    // none of them, about 5 % (BENCHMARKS.md).
    float kappa = lattice_own_widths(nv);
    float narrowest = beta * (1.0 - kappa * (1.0 - frame.env_lattice_across.y));
    vec4 read = frame.env_sharp_read;
    float sharp_share = frame.env_sharp.z > 0 && narrowest < layer_beta(1)
        ? (step > 0.0 ? clamp((read.w - reach / step) / (read.w - read.z), 0.0, 1.0) : 1.0)
        : 0.0;
    if (kappa > 0.0 || sharp_share > 0.0) {
        return lattice_by_node(p, n, v, nv, vec4(tangent, step), vec4(sigma_p, reach, beta,
            sharp_share), kappa, half_count, pair, base);
    }
    vec3 sum = vec3(0.0);
    vec3 weights = vec3(0.0);
    for (int i = -half_count; i <= half_count; ++i) {
        float slope = float(i) * step;
        float gauss = lattice_node_weight(slope, sigma_p, reach);
        vec3 h = normalize(tangent * slope + n);
        float vh = dot(v, h);
        vec3 s;
        vec3 weight;
        if (gauss > 0.0 && vh > 0.0 && lookup_weight(p, n, v, nv, h, vh, gauss, s, weight)) {
            s = across_mean(s, h, vh, lattice_across_variance(sigma, dot(n, h)));
            sum += weight * layered_radiance_pair(s, pair);
            weights += weight;
        }
    }
    return normalized_lookups(p, nv, sum, weights);
}

// The blur of the grid's node at slopes (x, y) with half vector h (twin: `node_blur`, which
// derives it): β scaled by the geometric mean of the reflection's Jacobian there against its
// value at the centre (2 along the plane, 2·nv across).
float node_blur(vec3 v, vec3 h, vec3 tangent, vec3 bitangent, float x, float y, float beta,
    float nv) {
    float inv_len = inversesqrt(1.0 + x * x + y * y);
    float vh = dot(v, h);
    vec3 dh_x = (tangent - h * dot(h, tangent)) * inv_len;
    vec3 dh_y = (bitangent - h * dot(h, bitangent)) * inv_len;
    float j_x = 2.0 * sqrt(dot(v, dh_x) * dot(v, dh_x) + vh * vh * dot(dh_x, dh_x));
    float j_y = 2.0 * sqrt(dot(v, dh_y) * dot(v, dh_y) + vh * vh * dot(dh_y, dh_y));
    return beta * sqrt(j_x * j_y / (4.0 * nv));
}

// A grid's blur share at nv: its own, but at least frame.env_grid_grazing.x towards grazing, a
// smoothstep from nv = .y to .z (twin: `grid_blur_share`).
float grid_blur_share(float share, float nv) {
    vec4 g = frame.env_grid_grazing;
    float x = clamp((nv - g.y) / (g.z - g.y), 0.0, 1.0);
    return max(share, g.x * (1.0 - smoothstep01(x)));
}

// The wider-lobe quadrature (twin: `specular_grid`, whose doc derives it): a grid of Beckmann
// slopes from the lobe's Gaussian less the lookups' blur, each read at its node's blur from the
// layers at `base`; `grid` its constants (frame.env_grid or env_variate_grid: t, spacing, reach,
// most nodes on each side along the plane).
vec3 specular_grid(LacquerParams p, vec3 n, vec3 v, float nv, int base, vec4 grid) {
    vec3 tangent, bitangent;
    incidence_frame(n, v, nv, tangent, bitangent);
    float share = grid_blur_share(grid.x, nv);
    float spacing = grid.y;
    float reach = grid.z;
    float sigma = p.beckmann_m * 0.70710678;
    float beta = 2.0 * nv * sigma * share;
    float var_along = sigma * sigma - (0.5 * beta) * (0.5 * beta);
    float var_across = sigma * sigma - (0.5 * beta / nv) * (0.5 * beta / nv);
    float step_across = spacing * 0.5 * beta / nv;
    float step_along = max(spacing * 0.5 * beta, reach * sqrt(var_along) / grid.w);
    int half_along = whole_to_int(ceil(reach * sqrt(var_along) / step_along));
    int half_across = whole_to_int(ceil(reach * sqrt(var_across) / step_across));
    vec3 sum = vec3(0.0);
    vec3 weights = vec3(0.0);
    for (int i = -half_along; i <= half_along; ++i) {
        for (int j = -half_across; j <= half_across; ++j) {
            float x = float(i) * step_along;
            float y = float(j) * step_across;
            float r = sqrt(x * x / var_along + y * y / var_across);
            if (r >= reach) {
                continue;
            }
            float scale = exp(-0.5 * r * r) * lattice_taper(r / reach);
            vec3 h = normalize(n + tangent * x + bitangent * y);
            float vh = dot(v, h);
            if (vh > 0.0) {
                float blur = node_blur(v, h, tangent, bitangent, x, y, beta, nv);
                add_lookup(p, n, v, nv, h, vh, scale, blur, base, sum, weights);
            }
        }
    }
    return normalized_lookups(p, nv, sum, weights);
}

// Filtered importance sampling (twin: `specular_quadrature`): the weighted mean of the lookups
// times the directional albedo A(nv), Σ w·L / Σ w · A(nv), exact in a white furnace at every nv.
vec3 specular_fis(LacquerParams p, vec3 n, vec3 v, float nv, int samples, int base) {
    vec3 tangent, bitangent;
    incidence_frame(n, v, nv, tangent, bitangent);
    float m2 = p.beckmann_m * p.beckmann_m;
    vec3 sum = vec3(0.0);
    vec3 weights = vec3(0.0);
    for (int i = 0; i < samples; ++i) {
        float u = (float(i) + 0.5) / float(samples);
        // The Fibonacci lattice (twin: `fibonacci_point`): the azimuth's fraction of a turn in
        // 24-bit fixed point, exact in f32.
        float w = float((uint(i) * FIBONACCI_STEP) >> 8u) * (1.0 / 16777216.0);
        // u = 1 − exp(−tan²θ_H/m²): the Beckmann lobe's distribution of D·cos θ_H.
        float rest = 1.0 - u;
        float tan2 = -m2 * log(rest);
        float cos_h = inversesqrt(1.0 + tan2);
        float sin_h = sqrt(tan2) * cos_h;
        float phi = 2.0 * PI * w;
        vec3 h = tangent * (sin_h * cos(phi)) + bitangent * (sin_h * sin(phi)) + n * cos_h;
        float vh = dot(v, h);
        if (vh > 0.0) {
            // pdf(s) = D·cos θ_H/(4·V·H) with D = (1 − u)/(π m² cos⁴θ_H); the lookup's lobe
            // 2πβ² covers 1/(samples·pdf).
            float pdf = rest / (4.0 * PI * m2 * cos_h * cos_h * cos_h * vh);
            float beta = sqrt(1.0 / (2.0 * PI * float(samples) * pdf));
            add_lookup(p, n, v, nv, h, vh, 1.0, beta, base, sum, weights);
        }
    }
    return normalized_lookups(p, nv, sum, weights);
}

// ∫ f_spec(N, V, s)·L(s)·(N·s) dω_s at a surface point (unit n, v; nv = N·V > 0): the bright
// lights, plus the residual's lookups by the lattice, the grid, filtered importance sampling, or
// two of them blended, as `quadrature_shares` says for the material, with `samples` lobe samples
// for filtered importance sampling; the grid serves the points the camera sees (samples above
// ENV_HIT_SAMPLES: ENV_SAMPLES, or ENV_VARIATE_SAMPLES for `paper`'s control variate), not a
// path's hits (twin: `brdf_specular`).
vec3 brdf_environment_specular(LacquerParams p, vec3 n, vec3 v, float nv, int samples) {
    bool camera = samples > ENV_HIT_SAMPLES;
    vec3 shares = quadrature_shares(p.beckmann_m, camera);
    // Where the camera looks the grid and filtered importance sampling read the rough split, and
    // the lattice from frame.env_lattice_share.y up (below it the rough split's blocks are too
    // wide for the lobe); at a path's hit every quadrature reads the first split.
    bool lattice_rough = camera && p.beckmann_m >= frame.env_lattice_share.y;
    int rough_base = camera ? frame.env_rough.x : 0;
    float rough_share = camera ? shares.y + shares.z : 0.0;
    if (lattice_rough) {
        rough_share += shares.x;
    }
    vec3 lookups = vec3(0.0);
    if (shares.x > 0.0) {
        lookups += shares.x * specular_lattice(p, n, v, nv, lattice_rough ? rough_base : 0);
    }
    if (shares.y > 0.0) {
        // paper's control variate reads the cheaper grid (twin: `grid_for`).
        vec4 grid = samples == ENV_VARIATE_SAMPLES ? frame.env_variate_grid : frame.env_grid;
        lookups += shares.y * specular_grid(p, n, v, nv, rough_base, grid);
    }
    if (shares.z > 0.0) {
        lookups += shares.z * specular_fis(p, n, v, nv, samples, rough_base);
    }
    vec3 bright = vec3(0.0);
    if (rough_share < 1.0) {
        bright += (1.0 - rough_share) * bright_specular(p, n, v, nv);
    }
    if (rough_share > 0.0) {
        vec3 rough_lights = p.beckmann_m <= frame.env_lattice_share.z
            ? binned_rough_bright_specular(p, n, v, nv)
            : rough_bright_specular(p, n, v, nv);
        bright += rough_share * rough_lights;
    }
    return lookups + bright;
}

#endif
