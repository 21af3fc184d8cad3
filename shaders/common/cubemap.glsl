// Cube-map and equirectangular geometry of SPEC §4; the Rust twin is src/environment/cube.rs
// (read its table of the Vulkan face coordinates). Change both together.
#ifndef CUBEMAP_GLSL
#define CUBEMAP_GLSL

#include "math.glsl"

// Unnormalised direction of face coordinates (sc, tc) ∈ [−1, 1]² on face 0..5 (+X −X +Y −Y +Z −Z).
vec3 face_direction(int face, float sc, float tc) {
    switch (face) {
    case 0: return vec3(1.0, -tc, -sc);
    case 1: return vec3(-1.0, -tc, sc);
    case 2: return vec3(sc, 1.0, tc);
    case 3: return vec3(sc, -1.0, -tc);
    case 4: return vec3(sc, -tc, 1.0);
    default: return vec3(-sc, -tc, -1.0);
    }
}

// The face's axis and the directions sc and tc grow along (from the table above).
void face_frame(int face, out vec3 axis, out vec3 s_dir, out vec3 t_dir) {
    switch (face) {
    case 0: axis = vec3(1, 0, 0); s_dir = vec3(0, 0, -1); t_dir = vec3(0, -1, 0); break;
    case 1: axis = vec3(-1, 0, 0); s_dir = vec3(0, 0, 1); t_dir = vec3(0, -1, 0); break;
    case 2: axis = vec3(0, 1, 0); s_dir = vec3(1, 0, 0); t_dir = vec3(0, 0, 1); break;
    case 3: axis = vec3(0, -1, 0); s_dir = vec3(1, 0, 0); t_dir = vec3(0, 0, -1); break;
    case 4: axis = vec3(0, 0, 1); s_dir = vec3(1, 0, 0); t_dir = vec3(0, -1, 0); break;
    default: axis = vec3(0, 0, -1); s_dir = vec3(-1, 0, 0); t_dir = vec3(0, -1, 0); break;
    }
}

// (face, sc, tc) of a direction by the Vulkan face-selection table (src/environment/cube.rs
// `direction_to_face`; ties go to X, then Y, then Z), with sc and tc the direction's components
// along the face's frame (`face_frame`) over its major one.
void select_face(vec3 d, out int face, out vec2 st) {
    vec3 a = abs(d);
    float major;
    vec3 s_dir;
    vec3 t_dir;
    if (a.x >= a.y && a.x >= a.z) {
        bool pos = d.x >= 0.0;
        face = pos ? 0 : 1;
        major = a.x;
        s_dir = vec3(0.0, 0.0, pos ? -1.0 : 1.0);
        t_dir = vec3(0.0, -1.0, 0.0);
    } else if (a.y >= a.z) {
        bool pos = d.y >= 0.0;
        face = pos ? 2 : 3;
        major = a.y;
        s_dir = vec3(1.0, 0.0, 0.0);
        t_dir = vec3(0.0, 0.0, pos ? 1.0 : -1.0);
    } else {
        bool pos = d.z >= 0.0;
        face = pos ? 4 : 5;
        major = a.z;
        s_dir = vec3(pos ? 1.0 : -1.0, 0.0, 0.0);
        t_dir = vec3(0.0, -1.0, 0.0);
    }
    st = vec2(dot(d, s_dir), dot(d, t_dir)) / major;
}

float texel_coord(uint i, uint face_size) {
    return 2.0 * (float(i) + 0.5) / float(face_size) - 1.0;
}

// Unit direction through texel (i, j) and its solid angle (2/M)²/(1 + sc² + tc²)^{3/2}.
vec3 texel_direction(int face, uint i, uint j, uint face_size, out float solid_angle) {
    vec3 d = face_direction(face, texel_coord(i, face_size), texel_coord(j, face_size));
    float inv_len = inversesqrt(dot(d, d));
    float h = 2.0 / float(face_size);
    solid_angle = h * h * inv_len * inv_len * inv_len;
    return d * inv_len;
}

// Index of texel (f, i, j) in a cube stored face after face, row after row.
uint cube_index(int face, uint i, uint j, uint face_size) {
    return (uint(face) * face_size + j) * face_size + i;
}

// World → environment frame: the environment turned by ρ about +Y; (c, s) = (cos ρ, sin ρ).
vec3 world_to_environment(vec3 d, float c, float s) {
    return vec3(d.x * c - d.z * s, d.y, d.x * s + d.z * c);
}

// SPEC §4: u = ½ + atan2(x, −z)/2π, v = acos(y)/π (v through atan2: accurate at the poles).
vec2 direction_to_equirect(vec3 d) {
    float u = 0.5 + atan2_accurate(d.x, -d.z) / (2.0 * PI);
    float v = atan2_accurate(length(d.xz), d.y) / PI;
    return vec2(u, v);
}

#endif
